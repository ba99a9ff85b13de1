"""Python client for strata-server: standard library only (numpy only for render_array
and render_arrays).

    from strata_client import Client, ProblemError

    with Client("http://127.0.0.1:7070") as strata:
        version = strata.edit([{"op": "set_camera", "eye": [0, 3, 10]}])
        report = strata.commit()              # a RebuildReport: report.tlas.action
        png = strata.render(640, 360)
        strata.undo()                         # takes the edit back, as a new version

AsyncClient has the same methods as coroutines. See clients/python/README.md and
protocol/README.md.
"""

from strata_client import animation, bulk, lod, mesh_edits
from strata_client._version import __version__
from strata_client.aio import AsyncClient
from strata_client.arrays import MISS, FrameArrays
from strata_client.client import Client
from strata_client.errors import (BadRequestError, ForbiddenError, NotFoundError,
                                  NothingToUndoError, ProblemError, SceneConflictError,
                                  TooLargeError, TooManyConnectionsError,
                                  UnauthorizedError, UnavailableError, UnprocessableError,
                                  VersionMismatchError)
from strata_client.png import decode_png
from strata_client.results import (Asset, AssetCounts, AssetDeleteResult, BlasEntry,
                                   CommitPhases, Compaction, Frame, History, HistoryEntry,
                                   HistoryStack, Hit, ImportResult, KeptIds, MemoryBytes, Page,
                                   Problem, RebuildReport, ReimportResult, RenderInfo,
                                   SceneBudget, SceneSummary, TlasMerge, TlasReport, UndoResult)

__all__ = [
    "__version__", "animation", "bulk", "lod", "mesh_edits", "Client", "AsyncClient",
    "decode_png",
    "ProblemError", "BadRequestError", "UnauthorizedError", "NotFoundError",
    "NothingToUndoError", "VersionMismatchError", "TooLargeError", "UnprocessableError",
    "TooManyConnectionsError", "UnavailableError", "SceneConflictError", "ForbiddenError",
    "Problem", "RebuildReport", "TlasReport", "TlasMerge", "BlasEntry", "MemoryBytes",
    "CommitPhases", "RenderInfo", "Frame", "Hit", "ImportResult", "Page", "UndoResult",
    "History", "HistoryEntry", "HistoryStack", "FrameArrays", "MISS", "SceneSummary",
    "SceneBudget", "Compaction", "Asset", "AssetCounts", "AssetDeleteResult", "ReimportResult",
    "KeptIds",
]
