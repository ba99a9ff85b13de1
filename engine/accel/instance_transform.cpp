#include "engine/accel/instance_transform.h"

#include <embree3/rtcore.h>

#include "engine/core/srt.h"

namespace strata {

void set_instance_transform(RTCGeometry g, const float* world, const std::vector<Affine>& keys,
                            MotionInterpolation how) {
    if (keys.empty()) {
        rtcSetGeometryTimeStepCount(g, 1);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, world);
        return;
    }
    rtcSetGeometryTimeStepCount(g, static_cast<unsigned>(keys.size()));
    if (how == MotionInterpolation::Linear) {
        for (unsigned k = 0; k < keys.size(); ++k)
            rtcSetGeometryTransform(g, k, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, keys[k].m.data());
        return;
    }
    const std::vector<SrtParts> parts = srt_keys(keys);
    for (unsigned k = 0; k < parts.size(); ++k) {
        const SrtParts& p = parts[k];
        RTCQuaternionDecomposition qd;
        rtcInitQuaternionDecomposition(&qd);
        rtcQuaternionDecompositionSetScale(&qd, p.scale.x, p.scale.y, p.scale.z);
        rtcQuaternionDecompositionSetSkew(&qd, p.skew.x, p.skew.y, p.skew.z);
        rtcQuaternionDecompositionSetQuaternion(&qd, p.rotation.w, p.rotation.x, p.rotation.y,
                                                p.rotation.z);
        rtcQuaternionDecompositionSetTranslation(&qd, p.translation.x, p.translation.y,
                                                 p.translation.z);
        rtcSetGeometryTransformQuaternion(g, k, &qd);
    }
}

void set_instance(RTCGeometry g, RTCScene blas, const float* world, const std::vector<Affine>& keys,
                  MotionInterpolation how, uint32_t mask) {
    rtcSetGeometryInstancedScene(g, blas);
    set_instance_transform(g, world, keys, how);
    rtcSetGeometryMask(g, mask);
    rtcCommitGeometry(g);
}

}  // namespace strata
