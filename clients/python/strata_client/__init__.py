"""Python client for strata-server: standard library only (numpy only for Client.render_array).

    from strata_client import Client, ProblemError

    with Client("http://127.0.0.1:7070") as strata:
        version = strata.edit([{"op": "set_camera", "eye": [0, 3, 10]}])
        report = strata.commit()
        png = strata.render(640, 360)

See clients/python/README.md and protocol/README.md.
"""

from strata_client.client import Client, ProblemError, RenderInfo
from strata_client.png import decode_png

__all__ = ["Client", "ProblemError", "RenderInfo", "decode_png"]
