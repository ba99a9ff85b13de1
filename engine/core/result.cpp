#include "engine/core/result.h"

namespace strata {

const char* error_code_name(ErrorCode code) {
    switch (code) {
        case ErrorCode::InvalidArgument: return "invalid_argument";
        case ErrorCode::NotFinite: return "not_finite";
        case ErrorCode::UnknownId: return "unknown_id";
        case ErrorCode::DuplicateId: return "duplicate_id";
        case ErrorCode::OutOfRange: return "out_of_range";
        case ErrorCode::DegenerateTransform: return "degenerate_transform";
        case ErrorCode::InUse: return "in_use";
        case ErrorCode::Cycle: return "cycle";
        case ErrorCode::EmptyMesh: return "empty_mesh";
        case ErrorCode::StaleHandle: return "stale_handle";
        case ErrorCode::TooLarge: return "too_large";
        case ErrorCode::VersionMismatch: return "version_mismatch";
        case ErrorCode::NothingToUndo: return "nothing_to_undo";
        case ErrorCode::Cancelled: return "cancelled";
        case ErrorCode::Storage: return "storage";
        case ErrorCode::Internal: return "internal";
    }
    return "internal";
}

std::string Error::describe() const {
    std::string out;
    if (edit_index != NO_INDEX) {
        out += "edit " + std::to_string(edit_index);
        if (!field.empty()) out += " (" + field + ")";
        out += ": ";
    } else if (!field.empty()) {
        out += field + ": ";
    }
    out += message;
    return out;
}

}  // namespace strata
