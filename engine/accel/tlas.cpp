#include "engine/accel/tlas.h"

namespace strata {

const char* tlas_kind_name(TlasKind k) {
    return k == TlasKind::Embree ? "embree" : "incremental";
}

std::optional<TlasKind> parse_tlas_kind(std::string_view name) {
    if (name == "incremental") return TlasKind::Incremental;
    if (name == "embree") return TlasKind::Embree;
    return std::nullopt;
}

}  // namespace strata
