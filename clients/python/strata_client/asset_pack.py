"""What import_asset uploads: the model alone, or a tar of the model and the files it names.

An .obj's `mtllib` files and the `map_Kd` images they name (relative to the MTL's folder, then
the OBJ's), and a .gltf's external `buffers` and `images` URIs, are packed with the model into a
POSIX tar archive in memory, each at its path under the deepest folder that holds them all; the
server finds them relative to the model's folder (POST /v1/assets, protocol/README.md
"Archives"). A referenced file that is missing raises FileNotFoundError, an absolute reference
or a file outside the model's folder that is not a .mtl, .bin, .png or .jpg ValueError (an
untrusted model must not make the upload carry arbitrary local files), before anything is sent.
"""

import io
import json
import os
import tarfile
import urllib.parse
from typing import List, NamedTuple


class PackedAsset(NamedTuple):
    data: bytes            # the model file, or the tar archive
    archive: bool          # data is a tar of the model and side_files
    model_path: str        # the model's path inside the archive
    side_files: List[str]  # archive paths of the files packed with it


_OUTSIDE_KINDS = (".mtl", ".bin", ".png", ".jpg", ".jpeg")


def _resolve(reference: str, who: str, bases: List[str], model_folder: str) -> str:
    ref = reference.replace("\\", "/")
    if ref.startswith("/") or (len(ref) >= 2 and ref[1] == ":"):
        raise ValueError(f"{who} names '{reference}', an absolute path: the server looks side "
                         "files up only inside the upload; make the reference relative")
    tried = []
    for base in bases:
        path = os.path.normpath(os.path.join(base, ref))
        if os.path.isfile(path):
            # A model from elsewhere must not make the upload carry any file it likes
            # (../../.ssh/id_rsa): outside the model's folder only these kinds are packed.
            outside = os.path.relpath(path, model_folder).split(os.sep)[0] == ".."
            if outside and os.path.splitext(path)[1].lower() not in _OUTSIDE_KINDS:
                raise ValueError(f"{who} names '{reference}' ({path}): outside the model's "
                                 "folder only .mtl, .bin, .png and .jpg files are packed")
            return path
        tried.append(path)
    raise FileNotFoundError(f"{who} names '{reference}', which is not a readable file "
                            f"({' or '.join(tried)})")


def _obj_side_files(model: str, text: str) -> List[str]:
    folder = os.path.dirname(model)
    files: List[str] = []
    mtls: List[str] = []
    for line in text.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "mtllib":
            for name in words[1:]:
                mtl = _resolve(name, os.path.basename(model) + " (mtllib)", [folder], folder)
                if mtl not in mtls:
                    mtls.append(mtl)
    files += mtls
    for mtl in mtls:
        with open(mtl, "r", encoding="utf-8", errors="replace") as f:
            for line in f:
                words = line.split()
                # The importer binds map_Kd only; the file name is its last word.
                if len(words) >= 2 and words[0] == "map_Kd":
                    files.append(_resolve(words[-1], os.path.basename(mtl) + " (map_Kd)",
                                          [os.path.dirname(mtl), folder], folder))
    return files


def _gltf_side_files(model: str, text: str) -> List[str]:
    try:
        doc = json.loads(text)
    except ValueError:
        return []  # the server names what is wrong
    files: List[str] = []
    if not isinstance(doc, dict):
        return files
    for kind in ("buffers", "images"):
        items = doc.get(kind)
        if not isinstance(items, list):
            continue
        for i, item in enumerate(items):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or not uri or uri.startswith("data:"):
                continue
            files.append(_resolve(urllib.parse.unquote(uri),
                                  f"{os.path.basename(model)} ({kind}[{i}])",
                                  [os.path.dirname(model)], os.path.dirname(model)))
    return files


def pack_asset(path: str) -> PackedAsset:
    """Reads `path` and, for an .obj or .gltf that names other files, packs them all in a tar."""
    model = os.path.normpath(os.path.abspath(path))
    with open(model, "rb") as f:
        data = f.read()
    ext = os.path.splitext(model)[1].lower()
    side: List[str] = []
    text = data.decode("utf-8", errors="replace")
    if ext == ".obj":
        side = _obj_side_files(model, text)
    elif ext == ".gltf":
        side = _gltf_side_files(model, text)
    side = [p for i, p in enumerate(side) if p != model and p not in side[:i]]
    if not side:
        return PackedAsset(data, False, os.path.basename(model), [])
    root = os.path.commonpath([os.path.dirname(p) for p in [model] + side])
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w", format=tarfile.GNU_FORMAT) as tar:
        names = []
        for p in [model] + side:
            name = os.path.relpath(p, root).replace(os.sep, "/")
            names.append(name)
            if p == model:
                content = data
            else:
                with open(p, "rb") as f:
                    content = f.read()
            info = tarfile.TarInfo(name)
            info.size = len(content)
            info.mode = 0o644
            tar.addfile(info, io.BytesIO(content))
    return PackedAsset(buffer.getvalue(), True, names[0], names[1:])
