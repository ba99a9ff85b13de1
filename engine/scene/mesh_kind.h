#pragma once
// What a mesh's primitives are (OptiX's build input types, Embree's geometry types): triangles,
// points (spheres, one per vertex, each with its radius) or curves (strands of control vertices,
// each with a radius: Embree's round tubes or flat ray-facing ribbons in one of four bases).
// A mesh's kind is fixed when it is added. Its edits are the same as for triangles: moving
// vertices or changing radii marks the positions dirty, changing the number of vertices or the
// strands the topology. Embree 3 has no refit for sphere and curve BVHs, so for points and curves
// both rebuild that mesh's BVH (accel_graph.cpp), and nothing else.
//
// A curve mesh's topology is its strands: the number of control vertices of each, in vertex
// order (USD's curveVertexCounts). Its primitives are the strands' segments, numbered strand by
// strand: hits, picks and primitive-id AOVs report that number.

#include <cstdint>
#include <string>
#include <vector>

namespace strata {

enum class MeshKind : uint8_t { Triangles, Points, Curves };
/// The curve's basis (how control vertices make a segment).
enum class CurveBasis : uint8_t { Linear, Bezier, BSpline, CatmullRom };
/// Round: a tube of varying radius; flat: a ribbon that faces the ray.
enum class CurveStyle : uint8_t { Round, Flat };

/// The fewest control vertices a strand of `basis` holds.
constexpr uint32_t min_strand_vertices(CurveBasis basis) {
    return basis == CurveBasis::Linear ? 2 : 4;
}

/// The segments of a strand of `n` control vertices, or 0 when `n` is not a valid count for
/// the basis (linear: n >= 2; Bezier: n = 3k + 1, k >= 1; B-spline and Catmull-Rom: n >= 4).
constexpr uint32_t strand_segments(CurveBasis basis, uint32_t n) {
    if (n < min_strand_vertices(basis)) return 0;
    switch (basis) {
        case CurveBasis::Linear: return n - 1;
        case CurveBasis::Bezier: return (n - 1) % 3 == 0 ? (n - 1) / 3 : 0;
        default: return n - 3;
    }
}

/// Why `strands` cannot be the topology of a curve mesh of `vertex_count` vertices in `basis`
/// (empty when it can); `bad` receives the index of the first bad strand (the count when the
/// sum is wrong).
std::string strands_problem(CurveBasis basis, const std::vector<uint32_t>& strands,
                            std::size_t vertex_count, std::size_t& bad);

/// The segments of all strands (valid ones).
uint64_t curve_segment_count(CurveBasis basis, const std::vector<uint32_t>& strands);

/// The first control vertex of each segment, strand by strand: Embree's curve index buffer.
std::vector<uint32_t> curve_segment_starts(CurveBasis basis, const std::vector<uint32_t>& strands);

const char* mesh_kind_name(MeshKind k);

}  // namespace strata
