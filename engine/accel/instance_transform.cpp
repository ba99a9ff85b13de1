#include "engine/accel/instance_transform.h"

#include <embree3/rtcore.h>

namespace strata {

void set_instance_transform(RTCGeometry g, const float* world, const std::vector<Affine>& keys) {
    if (keys.empty()) {
        rtcSetGeometryTimeStepCount(g, 1);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, world);
        return;
    }
    rtcSetGeometryTimeStepCount(g, static_cast<unsigned>(keys.size()));
    for (unsigned k = 0; k < keys.size(); ++k)
        rtcSetGeometryTransform(g, k, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, keys[k].m.data());
}

}  // namespace strata
