"""Frames as numpy arrays: what a render with format "npz" answers (protocol/README.md, "Frames
as arrays"), read with numpy alone, and the frame's ID manifests to turn id AOV values into client
ids. numpy is imported only when a frame is read."""

import io
from dataclasses import dataclass, field
from typing import Any, Dict, Optional

from strata_client.results import Frame, RenderInfo

#: The value id AOVs hold where nothing was hit.
MISS = 0xFFFFFFFF


@dataclass(frozen=True)
class FrameArrays:
    """A frame's arrays by name: "beauty" (float32, height x width x 3, linear) and one per AOV
    asked for ("depth", "instance_id", ...), with `names[aov][value]`, the client id behind each
    value of the "instance_id" and "mesh_id" arrays in this frame."""

    arrays: Dict[str, Any] = field(repr=False)
    names: Dict[str, Dict[int, str]]
    info: RenderInfo

    def __getitem__(self, name: str) -> Any:
        return self.arrays[name]

    def __contains__(self, name: object) -> bool:
        return name in self.arrays

    def client_id(self, aov: str, value: int) -> Optional[str]:
        """The client id of `value` in the id AOV `aov`; None for the sky (or an unknown value)."""
        return self.names.get(aov, {}).get(int(value))

    def client_ids(self, aov: str) -> Any:
        """The id AOV `aov` as a numpy array of client ids (None where nothing was hit)."""
        import numpy  # noqa: PLC0415 (numpy only when arrays are read)

        lookup = self.names.get(aov, {})
        values = self.arrays[aov]
        out = numpy.empty(values.shape, dtype=object)
        for value in numpy.unique(values).tolist():
            out[values == value] = lookup.get(value)
        return out


def frame_arrays(frame: Frame) -> FrameArrays:
    """The arrays of an npz frame."""
    import numpy  # noqa: PLC0415

    with numpy.load(io.BytesIO(frame.image), allow_pickle=False) as npz:
        loaded = {name: npz[name] for name in npz.files}
    names: Dict[str, Dict[int, str]] = {}
    for key in [k for k in loaded if k.endswith(".ids")]:
        aov = key[: -len(".ids")]
        ids = loaded.pop(key).tolist()
        texts = loaded.pop(aov + ".names").tolist()
        names[aov] = dict(zip(ids, texts))
    return FrameArrays(loaded, names, frame.info)
