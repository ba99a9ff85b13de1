#pragma once
// What the writers of statistics tables (engine/core/stat_table.h) share: the JSON members of a
// table (GET /v1/stats), and the Prometheus name and value of a row, one rule for every table
// (/metrics, server/metrics.h, and the generated docs).

#include <string>
#include <string_view>

#include "engine/core/stat_table.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// Sets one member of `j` per row of `table`: whole numbers as integers, the rest as numbers.
template <class S, std::size_t N>
void add_stats(Json& j, const StatSpec<S> (&table)[N], const S& s) {
    for (const StatSpec<S>& spec : table) {
        if (spec.field.integral())
            j[std::string(spec.name)] = spec.field.integer(s);
        else
            j[std::string(spec.name)] = spec.value(s);
    }
}

/// `prefix` + the row's name in base units (milliseconds become `_seconds`), `_total` for
/// cumulative rows.
template <class S>
std::string metric_name(std::string_view prefix, const StatSpec<S>& spec) {
    std::string name = std::string(prefix) + std::string(spec.name);
    if (spec.unit == StatUnit::Milliseconds && name.size() > 3 &&
        name.compare(name.size() - 3, 3, "_ms") == 0)
        name.replace(name.size() - 3, 3, "_seconds");
    return spec.cumulative ? name + "_total" : name;
}

/// The row's value in the unit of metric_name.
template <class S>
double metric_value(const StatSpec<S>& spec, const S& s) {
    const double v = spec.value(s);
    return spec.unit == StatUnit::Milliseconds ? v / 1000.0 : v;
}

}  // namespace strata::protocol
