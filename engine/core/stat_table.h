#pragma once
// One row type for every table of statistics: the engine's counters (engine/counters.h), the
// data directory's numbers (engine/durable/durable_stats.h) and the server's connection, stream
// and replica numbers (server/metrics.cpp). A row names a field of a stats struct, says what it
// is, its unit and whether it only grows; every writer (the JSON of /v1/stats, the Prometheus
// text, the generated docs) walks the tables. STRATA_STAT ties a row's name to its field.

#include <atomic>
#include <cstdint>
#include <string_view>

namespace strata {

/// What a statistic measures, for writers that name or scale by it.
enum class StatUnit : uint8_t { Count, Bytes, Seconds, Milliseconds };

/// Reads one numeric field of `S`.
template <class S>
class StatField {
public:
    constexpr StatField(uint64_t S::*f) : m_count(f) {}               // NOLINT: implicit
    constexpr StatField(double S::*f) : m_real(f) {}                  // NOLINT
    constexpr StatField(bool S::*f) : m_flag(f) {}                    // NOLINT
    constexpr StatField(std::atomic<uint64_t> S::*f) : m_atomic(f) {}  // NOLINT

    /// The value as a double (exact below 2^53; flags are 0 or 1).
    double operator()(const S& s) const {
        if (m_real) return s.*m_real;
        return double(integer(s));
    }
    /// True for whole-number fields (counts, sizes, flags).
    constexpr bool integral() const { return m_real == nullptr; }
    /// The value of a whole-number field.
    uint64_t integer(const S& s) const {
        if (m_count) return s.*m_count;
        if (m_flag) return s.*m_flag ? 1 : 0;
        if (m_atomic) return (s.*m_atomic).load(std::memory_order_relaxed);
        return uint64_t(s.*m_real);
    }

private:
    uint64_t S::*m_count = nullptr;
    double S::*m_real = nullptr;
    bool S::*m_flag = nullptr;
    std::atomic<uint64_t> S::*m_atomic = nullptr;
};

/// One row: the field's wire name (its name in the struct), how to read it, a help sentence,
/// its unit, and whether it is cumulative (a counter) or a gauge.
template <class S>
struct StatSpec {
    std::string_view name;
    StatField<S> field;
    std::string_view help;
    StatUnit unit = StatUnit::Count;
    bool cumulative = true;

    double value(const S& s) const { return field(s); }
};

/// A row's name and field from one token: `{STRATA_STAT(EngineCounters, commits), "help"}`.
#define STRATA_STAT(S, field) #field, ::strata::StatField<S>(&S::field)

}  // namespace strata
