#include "engine/scene/lod.h"

#include "engine/scene/field_table.h"

namespace strata {

Status check_lod_range(float near, float far) {
    if (far > near) return {};
    return failure(ErrorCode::InvalidArgument,
                   "lod_far (" + number_text(far) + ") must be above lod_near (" +
                       number_text(near) + ")",
                   "lod_far");
}

LodBands child_lod_bands(const LodBands* parent_bands, bool parent_lod,
                         const Affine& parent_world, float near, float far) {
    LodBands bands;
    if (parent_bands) bands = *parent_bands;
    if (parent_lod) {
        const Vec3 origin(parent_world.at(0, 3), parent_world.at(1, 3), parent_world.at(2, 3));
        bands.push_back(LodBand{origin, near, far});
    }
    return bands;
}

}  // namespace strata
