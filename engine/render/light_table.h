#pragma once
// The lights a launch samples by next-event estimation: the scene's point, spot and rect lights
// and every triangle of every visible instance whose material emits, in one table drawn from in
// proportion to an estimate of each entry's power (so a bright lamp is sampled more often than a
// dim one, and a large emitting triangle more often than a small one).
//
// Power estimates (mean over RGB): point 4 pi I c, spot 2 pi (1 - cos half-angle) I c, rect
// pi A I c, emitting triangle pi A e. Point and spot lights are delta lights and rect lights are
// not geometry: only next-event estimation sees them. Emitting triangles are also reached by
// bounce rays; both strategies are weighted by multiple importance sampling (power heuristic),
// for which emitter_pdf() gives the solid-angle density of choosing a point on an emitter.

#include <cstdint>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata {

/// A point on a light chosen for a receiver.
struct LightSample {
    Vec3 dir{0.0f};      ///< unit, from the receiver toward the light
    float distance = 0;  ///< to the chosen point (shadow rays stop short of it)
    /// Incident radiance over the solid-angle density of the choice: multiplied by the BRDF times
    /// the cosine at the receiver, it is the light's contribution.
    Vec3 weight{0.0f};
    float pdf = 0;  ///< solid-angle density when a bounce ray could also reach it; 0 otherwise
    bool valid = false;
};

/// An emitting triangle in world space.
struct EmitterTriangle {
    Vec3 p0, e1, e2;  ///< vertex 0 and the edges to vertices 1 and 2
    Vec3 emission;    ///< radiance, both sides
    float area = 0;
};

class LightTable {
public:
    /// Rebuilds the table from the lights and the emitting triangles.
    void build(std::vector<Light> lights, std::vector<EmitterTriangle> emitters);

    bool empty() const { return m_total <= 0.0f; }
    std::size_t light_count() const { return m_lights.size(); }
    std::size_t emitter_count() const { return m_emitters.size(); }

    /// Chooses an entry with `u_select` and a point on it with (u0, u1), as seen from `p`.
    LightSample sample(const Vec3& p, float u_select, float u0, float u1) const;

    /// The solid-angle density with which sample() chooses a point at distance `distance` on an
    /// emitting triangle of radiance `emission` seen at cosine `cos_light` (absolute) from the
    /// receiver. Zero when the table is empty.
    float emitter_pdf(const Vec3& emission, float distance, float cos_light) const;

private:
    struct Entry {
        uint32_t index;  ///< into m_lights below m_lights.size(), else into m_emitters
        float cdf;       ///< running sum of powers, this entry included
    };

    LightSample sample_light(const Light& l, const Vec3& p, float u0, float u1) const;
    LightSample sample_emitter(const EmitterTriangle& t, const Vec3& p, float u0, float u1) const;

    std::vector<Light> m_lights;
    std::vector<EmitterTriangle> m_emitters;
    std::vector<Entry> m_entries;
    float m_total = 0.0f;
};

/// The power estimate of a light and of an emitting triangle (see the file comment).
float light_power(const Light& l);
float emitter_power(const Vec3& emission, float area);

}  // namespace strata
