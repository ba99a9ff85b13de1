#include "engine/scene/mesh_kind.h"

namespace strata {

std::string strands_problem(CurveBasis basis, const std::vector<uint32_t>& strands,
                            std::size_t vertex_count, std::size_t& bad) {
    uint64_t sum = 0;
    for (std::size_t i = 0; i < strands.size(); ++i) {
        sum += strands[i];
        if (strand_segments(basis, strands[i]) != 0) continue;
        bad = i;
        const char* rule = basis == CurveBasis::Linear   ? "at least 2"
                           : basis == CurveBasis::Bezier ? "3k + 1 (4, 7, 10, ...)"
                                                         : "at least 4";
        return "strand " + std::to_string(i) + " has " + std::to_string(strands[i]) +
               " control vertices; this basis needs " + rule;
    }
    if (strands.empty()) {
        bad = 0;
        return "a curve mesh needs at least one strand";
    }
    if (sum != vertex_count) {
        bad = strands.size();
        return "the strands hold " + std::to_string(sum) + " control vertices but the mesh has " +
               std::to_string(vertex_count) + " (they must add up)";
    }
    return {};
}

uint64_t curve_segment_count(CurveBasis basis, const std::vector<uint32_t>& strands) {
    uint64_t n = 0;
    for (uint32_t s : strands) n += strand_segments(basis, s);
    return n;
}

std::vector<uint32_t> curve_segment_starts(CurveBasis basis,
                                           const std::vector<uint32_t>& strands) {
    std::vector<uint32_t> out;
    out.reserve(curve_segment_count(basis, strands));
    const uint32_t step = basis == CurveBasis::Bezier ? 3 : 1;
    uint32_t first = 0;
    for (uint32_t s : strands) {
        const uint32_t segments = strand_segments(basis, s);
        for (uint32_t k = 0; k < segments; ++k) out.push_back(first + k * step);
        first += s;
    }
    return out;
}

const char* mesh_kind_name(MeshKind k) {
    switch (k) {
        case MeshKind::Points: return "points";
        case MeshKind::Curves: return "curves";
        default: return "triangles";
    }
}

}  // namespace strata
