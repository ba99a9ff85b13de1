#include "engine/scene/animation.h"

#include <algorithm>
#include <cmath>

#include "engine/scene/field_table.h"

namespace strata {

namespace {

/// `time` wrapped into [first, last) for a looping animation; unchanged otherwise.
float wrapped(const std::vector<Keyframe>& keys, float time, bool loop) {
    const float first = keys.front().time;
    const float period = keys.back().time - first;
    if (!loop || !(period > 0.0f)) return time;
    const double r = std::fmod(double(time) - double(first), double(period));
    return float(double(first) + (r < 0.0 ? r + double(period) : r));
}

Affine between(const Keyframe& a, const Keyframe& b, float u, MotionInterpolation how) {
    const Affine t = interpolate(a.transform, b.transform, u, how);
    if (transform_problem(t)) return u < 0.5f ? a.transform : b.transform;
    return t;
}

/// Whether a key, or the wrap of a loop, lies strictly inside the frame [t0, t0 + d]: the
/// transform then bends inside it and two samples are not exact.
bool bends_inside(const std::vector<Keyframe>& keys, float t0, float d, bool loop) {
    const float u0 = wrapped(keys, t0, loop);
    const float u1 = u0 + d;
    if (loop && keys.back().time > keys.front().time && u1 > keys.back().time) return true;
    return std::any_of(keys.begin(), keys.end(),
                       [&](const Keyframe& k) { return k.time > u0 && k.time < u1; });
}

}  // namespace

Status check_keys(const std::vector<Affine>& motion, const std::vector<Keyframe>& animation) {
    if (motion.empty() || animation.empty()) return {};
    return failure(ErrorCode::InvalidArgument,
                   "motion keys or an animation, not both (an animation blurs over the frame by "
                   "itself)",
                   "animation");
}

Status check_launch_time(const std::optional<float>& time) {
    if (!time || std::abs(*time) <= MAX_SCENE_TIME) return {};
    return failure(std::isfinite(*time) ? ErrorCode::InvalidArgument : ErrorCode::NotFinite,
                   "time must be a finite scene time within " + number_text(MAX_SCENE_TIME) +
                       " seconds of 0",
                   "time");
}

Affine animation_at(const std::vector<Keyframe>& keys, float time, MotionInterpolation how,
                    bool loop) {
    const float t = wrapped(keys, time, loop);
    if (!(t > keys.front().time)) return keys.front().transform;
    if (!(t < keys.back().time)) return keys.back().transform;
    const auto next = std::upper_bound(keys.begin(), keys.end(), t,
                                       [](float v, const Keyframe& k) { return v < k.time; });
    const Keyframe& b = *next;
    const Keyframe& a = *(next - 1);
    if (t == a.time) return a.transform;  // on a key: exactly it (SRT parts round)
    return between(a, b, (t - a.time) / (b.time - a.time), how);
}

AnimatedPose animated_pose(const std::vector<Keyframe>& keys, const Timeline& clock,
                           MotionInterpolation how, bool loop) {
    AnimatedPose pose{animation_at(keys, clock.time, how, loop), {}};
    const float d = clock.frame_duration;
    if (keys.size() < 2 || !(d > 0.0f)) return pose;
    const std::size_t n = bends_inside(keys, clock.time, d, loop) ? FRAME_SAMPLES : 2;
    pose.keys.reserve(n);
    pose.keys.push_back(pose.start);
    bool moves = false;
    for (std::size_t k = 1; k < n; ++k) {
        const float t = clock.time + d * float(k) / float(n - 1);
        pose.keys.push_back(animation_at(keys, t, how, loop));
        moves = moves || !(pose.keys.back() == pose.start);
    }
    if (!moves) pose.keys.clear();
    return pose;
}

FramePose local_pose(const Placement& p, const Timeline& clock) {
    FramePose pose;
    pose.how = p.how;
    if (!p.animation.empty()) {
        AnimatedPose a = animated_pose(p.animation, clock, p.how, p.loop);
        pose.start = a.start;
        pose.keys = std::move(a.keys);
        return pose;
    }
    pose.start = p.transform;
    pose.keys.reserve(p.motion.size());
    for (const Affine& k : p.motion) pose.keys.push_back(p.transform * k);
    return pose;
}

namespace {

/// Key k of n of `pose` (its start when it has no keys).
template <class Pose>
Affine key_at(const Pose& pose, std::size_t k, std::size_t n, MotionInterpolation how) {
    if (pose.keys.empty()) return pose.start;
    if (pose.keys.size() == n) return pose.keys[k];
    return motion_at(pose.keys, float(k) / float(n - 1), how);
}

}  // namespace

FramePose compose(const PoseView& parent, const FramePose& child) {
    FramePose out;
    out.start = parent.start * child.start;
    // Srt when a side with keys asks for it: a turning group keeps its children rigid.
    const auto srt = [](const auto& p) {
        return !p.keys.empty() && p.how == MotionInterpolation::Srt;
    };
    out.how = srt(parent) || srt(child) ? MotionInterpolation::Srt : child.how;
    const std::size_t n = std::max(parent.keys.size(), child.keys.size());
    if (n == 0) return out;
    out.keys.reserve(n);
    for (std::size_t k = 0; k < n; ++k)
        out.keys.push_back(key_at(parent, k, n, out.how) * key_at(child, k, n, out.how));
    return out;
}

}  // namespace strata
