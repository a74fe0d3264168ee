"""The camera sweep's clips tracked once and kept: each clip's heights by every path (``camera_cost.heights``), on
disk beside the clip.

Tracking the paper preset's 80 clips by every path took about 38 minutes in a paper build (the floor path's joint fits),
and the camera page executes again for any change to the package; with this cache it reads them back in seconds.
An entry is keyed by the clip (its video's and ground truth's bytes, its shot, its colour, its rest height), the
object's shape and the code that tracks (the closure of this module), written atomically and read back in the same
form it was written, so an answer computed now and one read later are the same to the bit. One that cannot be read
is made again.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import json
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import scipy

from study.core import cache
from study.core.errors import OutputError
from study.core.progress import Progress
from study.methods import camera_cost
from study.methods.sweep import Clip
from study.see.scale import ObjectShape
from study.see.trajectory import Trajectory


def track_clips(clips: Sequence[Clip], shape: ObjectShape, progress: bool = True) -> list[camera_cost.Heights]:
    """``camera_cost.track_clips``, each clip's :class:`camera_cost.Heights` read from its cache entry where it has one,
    else made and kept there (:func:`entry`)."""
    code = cache.source_hash(*cache.closure(__name__))
    out = []
    with Progress("track the camera sweep", total=len(clips), show=progress, unit="clip") as bar:
        for clip in clips:
            out.append(heights(clip, shape, code))
            bar.update()
    return out


def heights(clip: Clip, shape: ObjectShape, code: str) -> camera_cost.Heights:
    """One clip's heights by every path, from its cache entry, or tracked now and kept; either way as
    :func:`decode` reads them."""
    path = entry(clip, shape, code)
    with cache.one_maker(path):  # two chapters of a build track a clip once
        try:
            return read(path)
        except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile):
            pass  # none yet, or not readable: made again
        data = encode(camera_cost.heights(clip, shape))
        with contextlib.suppress(OutputError):  # a folder that cannot be written: tracked, not kept
            cache.write_bytes_atomic(path, data)
        return decode(data)


def entry(clip: Clip, shape: ObjectShape, code: str) -> Path:
    """Where ``clip``'s heights are kept: beside the video, named by a key of all that makes them."""
    v = clip.video
    key = cache.key({"video": _digest(v.path), "truth": _digest(v.truth) if v.truth else None,
                     "shot": dataclasses.asdict(clip.shot), "track": dataclasses.asdict(v.track_config()),
                     "rest_height": v.rest_height, "shape": dataclasses.asdict(shape), "code": code,
                     "opencv": cv2.__version__, "numpy": np.__version__, "scipy": scipy.__version__})
    return v.path.with_name(f"{v.path.stem}.heights-{key}.npz")


def encode(h: camera_cost.Heights) -> bytes:
    """``h`` as the bytes of an .npz (no pickles): its arrays as they are, everything else as JSON."""
    arrays: dict[str, np.ndarray] = {"exact": h.exact}
    why: dict[str, str] = {}
    for name, got in h.paths.items():
        if isinstance(got, str):
            why[name] = got
        else:
            arrays[f"path/{name}"] = got
    tracks: dict[str, dict[str, Any]] = {}
    for name, traj in h.tracks.items():
        tracks[name] = {}
        for f in dataclasses.fields(traj):
            value = getattr(traj, f.name)
            if isinstance(value, np.ndarray):
                arrays[f"track/{name}/{f.name}"] = value
            elif isinstance(value, np.generic):
                tracks[name][f.name] = value.item()
            else:
                tracks[name][f.name] = str(value) if isinstance(value, Path) else value
    meta = {"why": why, "tracks": tracks, "paths": list(h.paths), "order": list(h.tracks)}
    buf = io.BytesIO()
    np.savez(buf, meta=np.array(json.dumps(meta)), **arrays)
    return buf.getvalue()


def read(path: str | Path) -> camera_cost.Heights:
    """The :class:`camera_cost.Heights` kept at ``path``."""
    return decode(Path(path).read_bytes())


def decode(data: bytes) -> camera_cost.Heights:
    """The :class:`camera_cost.Heights` that :func:`encode` made ``data`` of."""
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        meta = json.loads(str(z["meta"]))
        arrays = {k: z[k] for k in z.files if k != "meta"}
    paths = {name: meta["why"][name] if name in meta["why"] else arrays[f"path/{name}"] for name in meta["paths"]}
    tracks = {}
    for name in meta["order"]:
        fields = dict(meta["tracks"][name])
        fields.update({k.rpartition("/")[2]: a for k, a in arrays.items() if k.startswith(f"track/{name}/")})
        if fields.get("source") is not None:
            fields["source"] = Path(fields["source"])
        tracks[name] = Trajectory(**fields)
    return camera_cost.Heights(arrays["exact"], paths, tracks)


def _digest(path: Path) -> str:
    """The SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()
