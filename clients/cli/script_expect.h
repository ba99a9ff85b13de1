#pragma once
// A step's "expect": what its rebuild report must say, compiled when the script loads and checked
// against the report JSON each time the step plays (so it means the same over HTTP and embedded).
//
//   counts    version, tlas_instances, tlas_static_instances, tlas_dynamic_instances,
//             tlas_stale_copies, blas_rebuilds, blas_refits, primitives_built,
//             primitives_refit, clusters_rebuilt, clusters_refit: a number (exact) or
//             {"min": a, "max": b} (either bound optional)
//   tlas      the TLAS action: "none", "update" or "rebuild"
//   meshes    rebuilt, refit, released: the exact set of mesh ids, as an array (["a", "b"]) or,
//             for rebuilt and refit, as an object that also pins each reason
//             ({"a": "topology_changed"})
//   budgets   max_primitives_built (deterministic, always checked) and max_ms (the commit's
//             wall time: checked only with --budgets, so CI never depends on timing)
//
// Pick and list steps check the answer instead (ExpectTarget):
//
//   pick      hit (true or false: whether anything was hit), hit.instance and hit.mesh (ids),
//             hit.primitive, hit.user_id, hit.distance and version (counts)
//   list      count and version (counts), ids (the exact set of ids listed)
//
// Numbers and ids may use `{expr}` substitutions (script_template.h).

#include <optional>
#include <string>
#include <vector>

#include "clients/cli/script_template.h"

namespace strata::cli {

/// An exact count or bounds on it.
struct CountExpectation {
    std::optional<Expression> exact;
    std::optional<Expression> min;
    std::optional<Expression> max;
};

/// An exact set of mesh ids, optionally with the reason each must carry.
struct MeshSetExpectation {
    std::vector<StringTemplate> ids;
    std::vector<std::string> reasons;  ///< parallel to ids when `with_reasons`
    bool with_reasons = false;
};

/// One report field that did not match.
struct Mismatch {
    std::string field;
    std::string expected;
    std::string actual;
    std::string note;  ///< e.g. "missing: ball; unexpected: crate"
};

/// What an expectation is checked against: a rebuild report (commit, plan and render steps), a
/// pick step's `{"version", "hit"}` or a list step's `{"version", "count", "ids"}`.
enum class ExpectTarget : uint8_t { Report, Pick, List };

/// What a report (or an answer) must say.
class Expectation {
public:
    /// Compiles an "expect" object. `has_time`: the report will have `ms` (not a plan).
    static Outcome<Expectation> compile(const Json& v, const std::vector<std::string>& names,
                                        bool has_time, ExpectTarget target = ExpectTarget::Report);

    /// What did not match (empty: everything did). Fails only when an expression cannot be
    /// evaluated.
    Outcome<std::vector<Mismatch>> check(const Json& report, const Bindings& vars,
                                         bool budgets) const;

    /// Number of fields checked whatever the profile, and of budgets (checked with --budgets).
    std::size_t count_checks() const;
    std::size_t count_budgets() const;
    /// True when it checks a list of meshes (rebuilt, refit, released).
    bool names_meshes() const { return !m_meshes.empty(); }

private:
    static Outcome<Expectation> compile_answer(const Json& v, const std::vector<std::string>& names,
                                               ExpectTarget target);

    struct CountField {
        std::string name;  ///< wire name, e.g. "blas_rebuilds"
        CountExpectation expect;
        const char* parent = nullptr;  ///< where the checked document keeps it (nullptr: top)
        const char* member = nullptr;
    };
    struct TextField {
        std::string name;  ///< e.g. "hit.instance"
        StringTemplate expect;
        const char* parent = nullptr;
        const char* member = nullptr;
    };
    struct MeshField {
        std::string name;
        MeshSetExpectation expect;
    };
    std::vector<CountField> m_counts;
    std::optional<std::string> m_tlas;
    std::vector<MeshField> m_meshes;
    std::vector<TextField> m_texts;
    std::optional<bool> m_hit;  ///< pick: whether anything must be hit
    std::optional<Expression> m_max_ms;
    std::optional<Expression> m_max_primitives_built;
};

}  // namespace strata::cli
