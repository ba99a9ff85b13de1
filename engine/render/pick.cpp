#include "engine/render/pick.h"

#include <cmath>
#include <limits>

#include "engine/render/camera_rays.h"
#include "engine/scene/animation.h"

namespace strata {

Status check_pick_request(const PickRequest& request) {
    if (request.width == 0 || request.height == 0)
        return failure(ErrorCode::InvalidArgument, "width and height must be at least 1", "width");
    if (Status s = check_launch_time(request.time); !s) return s;
    if (request.pixels.empty())
        return failure(ErrorCode::InvalidArgument, "no pixel to pick", "pixels");
    if (request.pixels.size() > MAX_PICK_PIXELS)
        return failure(ErrorCode::TooLarge,
                       "a pick asks about at most " + std::to_string(MAX_PICK_PIXELS) +
                           " pixels, not " + std::to_string(request.pixels.size()),
                       "pixels");
    for (std::size_t i = 0; i < request.pixels.size(); ++i) {
        const PickPixel& p = request.pixels[i];
        if (p.x >= request.width || p.y >= request.height)
            return failure(ErrorCode::InvalidArgument,
                           "pixel (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
                               ") lies outside the " + std::to_string(request.width) + "x" +
                               std::to_string(request.height) + " image",
                           "pixels/" + std::to_string(i));
    }
    return {};
}

std::vector<std::optional<PickHit>> pick_pixels(const TlasStrategy& tlas, const FrameState& frame,
                                                const Scene& scene, const Camera& camera,
                                                const PickRequest& request) {
    const CameraRays rays(camera, request.width, request.height);
    std::vector<std::optional<PickHit>> out;
    out.reserve(request.pixels.size());
    // Picks see through cut-outs as frames do.
    const std::optional<HitTest> test = frame.hit_test();
    for (const PickPixel& p : request.pixels) {
        // The same arithmetic as a render's pixel-centre rays (CameraRays::directions).
        const float px = float(p.x) + 0.5f, py = float(p.y) + 0.5f;
        Vec3 dir;
        rays.directions(&px, &py, 1, &dir.x, &dir.y, &dir.z);
        RayHit1 ray{};
        ray.org_x = rays.eye().x;
        ray.org_y = rays.eye().y;
        ray.org_z = rays.eye().z;
        ray.dir_x = dir.x;
        ray.dir_y = dir.y;
        ray.dir_z = dir.z;
        ray.time = rays.time(0.0f);  // picks see the scene as the shutter opens
        ray.tfar = std::numeric_limits<float>::infinity();
        ray.mask = 0xFFFFFFFFu;
        ray.geom_id = ray.inst_id = ray.prim_id = INVALID_ID;
        tlas.intersect1(ray, false, test ? &*test : nullptr);
        if (ray.inst_id == INVALID_ID) {
            out.emplace_back();
            continue;
        }
        const InstanceRecord& inst = scene.instances().at_slot(ray.inst_id);
        const InstanceShade& shade = frame.instances[ray.inst_id];
        Vec3 n = shade.normals_at(ray.time) * Vec3(ray.ng_x, ray.ng_y, ray.ng_z);
        const float len2 = glm::dot(n, n);
        n = len2 > 0.0f ? n / std::sqrt(len2) : -dir;
        if (glm::dot(n, dir) > 0.0f) n = -n;
        PickHit hit;
        hit.instance = inst.id;
        hit.mesh = scene.mesh(inst.mesh).value()->id;
        hit.primitive = ray.prim_id;
        hit.distance = ray.tfar;
        hit.position = rays.eye() + ray.tfar * dir;
        hit.normal = n;
        hit.user_id = inst.user_id;
        hit.fields = save_fields<InstanceFields>(inst);
        hit.group_path = scene.group_path(inst.parent);
        out.emplace_back(std::move(hit));
    }
    return out;
}

}  // namespace strata
