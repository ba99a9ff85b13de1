"""Keyframe animation (protocol/README.md, "Animation"): an instance's transform given at scene
times, evaluated at the scene's time, which set_time moves (or one render's `time`).

    from strata_client import animation

    strata.edit([animation.animate("wheel", animation.spin(period=2.0), loop=True),
                 animation.animate_group("car", animation.keyframes(
                     [0, 4], [{"translate": [0, 0, 0]}, {"translate": [20, 0, 0]}])),
                 animation.set_time(0.0)])
    for frame in range(48):
        strata.edit([animation.set_time(frame / 24)])   # costs the animated instances only
        png = strata.render(640, 360)
    png = strata.render(640, 360, time=1.5)             # one frame at 1.5 s; the scene stays

Times are seconds. A keyframe's transform is relative to the instance's parent, in any form the
server takes ([12] or [16] numbers, or {"translate", "rotate_deg", "quaternion", "scale"}).
"""

import math
from typing import Any, Dict, Iterable, List, Optional, Sequence

Transform = Any  # a list of 12 or 16 numbers, a TRS dict, or a numpy array of shape (3, 4)


def _transform(t: Transform) -> Any:
    if hasattr(t, "tolist"):  # numpy
        t = t.tolist()
    if isinstance(t, list) and len(t) in (3, 4) and all(isinstance(r, list) for r in t):
        t = [float(v) for row in t for v in row]  # rows of a 3x4 or 4x4 matrix
    return t


def keyframes(times: Iterable[float], transforms: Iterable[Transform]) -> List[Dict[str, Any]]:
    """[{"time", "transform"}, ...] from matching sequences (numpy arrays welcome: times of
    shape (n,), transforms of shape (n, 3, 4) or (n, 12)). Times must increase."""
    ts = [float(t) for t in (times.tolist() if hasattr(times, "tolist") else times)]
    xs = [_transform(x) for x in transforms]
    if len(ts) != len(xs):
        raise ValueError(f"{len(ts)} times for {len(xs)} transforms")
    for i in range(1, len(ts)):
        if not ts[i] > ts[i - 1]:
            raise ValueError(f"keyframe times must increase: {ts[i - 1]} then {ts[i]}")
    return [{"time": t, "transform": x} for t, x in zip(ts, xs)]


def spin(period: float, *, axis: Sequence[float] = (0.0, 1.0, 0.0), turns: int = 1,
         start: float = 0.0, translate: Sequence[float] = (0.0, 0.0, 0.0),
         keys_per_turn: int = 4) -> List[Dict[str, Any]]:
    """Keyframes that turn an object `turns` times about `axis` (through `translate`) in
    `period` seconds from `start`: keys_per_turn keys a turn (at least 3, so that SRT
    interpolation, which turns the shorter way, goes round), for `animate(..., loop=True)`."""
    if keys_per_turn < 3:
        raise ValueError("a turn needs at least 3 keys (SRT turns the shorter way between two)")
    if not period > 0:
        raise ValueError("period must be > 0")
    n = math.sqrt(sum(float(a) * float(a) for a in axis))
    if n == 0:
        raise ValueError("axis has zero length")
    ax = [float(a) / n for a in axis]
    steps = keys_per_turn * turns
    out = []
    for k in range(steps + 1):
        half = math.pi * k / keys_per_turn  # half the angle: 2 pi k / keys_per_turn / 2
        s = math.sin(half)
        quaternion = [ax[0] * s, ax[1] * s, ax[2] * s, math.cos(half)]
        out.append({"time": start + period * k / steps,
                    "transform": {"translate": [float(v) for v in translate],
                                  "quaternion": quaternion}})
    return out


def animate(instance: str, keys: Sequence[Dict[str, Any]], *, loop: Optional[bool] = None,
            interpolation: Optional[str] = "srt") -> Dict[str, Any]:
    """An update_instance edit giving `instance` the keyframes `keys` ([] removes its
    animation); interpolation "srt" (the default: turns stay rigid) or "linear"."""
    return _animate({"op": "update_instance", "instance": instance}, keys, loop, interpolation)


def animate_group(group: str, keys: Sequence[Dict[str, Any]], *, loop: Optional[bool] = None,
                  interpolation: Optional[str] = "srt") -> Dict[str, Any]:
    """animate() for a group: everything below it moves with it."""
    return _animate({"op": "update_group", "group": group}, keys, loop, interpolation)


def _animate(edit: Dict[str, Any], keys: Sequence[Dict[str, Any]], loop: Optional[bool],
             interpolation: Optional[str]) -> Dict[str, Any]:
    edit["animation"] = list(keys)
    if loop is not None:
        edit["animation_loop"] = bool(loop)
    if interpolation is not None:
        edit["motion_interpolation"] = interpolation
    return edit


def set_time(time: Optional[float] = None,
             frame_duration: Optional[float] = None) -> Dict[str, Any]:
    """A set_time edit: the scene's time in seconds and/or how many seconds a frame spans (an
    animated instance blurs over it under an open shutter; 0: no blur)."""
    edit: Dict[str, Any] = {"op": "set_time"}
    if time is not None:
        edit["time"] = float(time)
    if frame_duration is not None:
        edit["frame_duration"] = float(frame_duration)
    return edit
