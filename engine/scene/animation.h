#pragma once
// Keyframe animation: an instance's or a group's transform given at scene times (Keyframe,
// types.h) and evaluated at the scene's time (Timeline). Between two keys the transform is
// interpolated as the object's motion_interpolation says (linear, or srt: rotations by slerp);
// before the first key it holds the first, after the last the last, unless the animation loops,
// when scene time wraps into [first, last). Over one frame (Timeline::frame_duration seconds from
// the scene time) a moving object gets motion keys, so a render with an open shutter blurs it as
// it moves. Evaluating touches the animated objects only: stepping time costs what they need.
//
// Poses over a frame compose down the scene graph (FramePose): a group's keys (its motion keys,
// or its animation sampled over the frame) times its child's give the child's world keys, both
// sampled at the same frame times; keys of different counts are resampled to the larger count,
// interpolated as the pair says (srt when either side asks for it).

#include <optional>
#include <vector>

#include "engine/scene/types.h"

namespace strata {

/// Most motion keys one frame of an animation is sampled into (when a keyframe or a loop's wrap
/// falls inside the frame; otherwise 2 are exact).
constexpr std::size_t FRAME_SAMPLES = 17;

/// The transform `keys` (at least one, times increasing) give at scene time `time`. An
/// interpolated transform that breaks the transform rule (a linear blend halfway through a half
/// turn is flat) is replaced by the nearer key's.
Affine animation_at(const std::vector<Keyframe>& keys, float time, MotionInterpolation how,
                    bool loop);

/// An instance or a group is placed by motion keys or by an animation, not both: an error at
/// `animation`.
Status check_keys(const std::vector<Affine>& motion, const std::vector<Keyframe>& animation);

/// A launch's own scene time (RenderRequest::time, PickRequest::time), when given: finite and
/// within MAX_SCENE_TIME; an error at "time".
Status check_launch_time(const std::optional<float>& time);

/// An animated instance over the frame that starts at `clock.time`.
struct AnimatedPose {
    Affine start;               ///< its transform at the frame's start (frame time 0)
    std::vector<Affine> keys;   ///< evenly spaced over the frame; empty: still during it
};

AnimatedPose animated_pose(const std::vector<Keyframe>& keys, const Timeline& clock,
                           MotionInterpolation how, bool loop);

/// Where an object is over one frame: `start` (its transform where no key applies: what
/// InstanceRecord::world holds) and `keys`, evenly spaced over frame time 0 to 1 (empty: still
/// during the frame), interpolated as `how` says.
struct FramePose {
    Affine start;
    std::vector<Affine> keys;
    MotionInterpolation how = MotionInterpolation::Linear;
};

/// The fields that place an instance or a group relative to its parent (scene.h's records).
struct Placement {
    const Affine& transform;
    const std::vector<Affine>& motion;
    const std::vector<Keyframe>& animation;
    bool loop;
    MotionInterpolation how;
};

/// An object's pose relative to its parent at `clock`: its animation's, or its transform (times
/// its motion keys, when it has some).
FramePose local_pose(const Placement& p, const Timeline& clock);

/// A parent's world pose where it is kept (GroupRecord's world, world_keys, world_interpolation).
struct PoseView {
    const Affine& start;
    const std::vector<Affine>& keys;
    MotionInterpolation how;
};

/// `child` under `parent`: the products of their keys, sampled at the same frame times.
FramePose compose(const PoseView& parent, const FramePose& child);

}  // namespace strata
