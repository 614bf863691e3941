"""The project's BVH reader and writer (motiondiff.data.formats.bvh) against bvhio, on real and on unusual files.

    /tmp/depvenv/bin/python bench/dependencies/bvh_io.py [--ds2-every 40] [--time-files 20]

Real files: every clip of bandai-ds1.zip and every k-th clip (sorted names) of bandai-ds2.zip from ../shared/data.
Both readers parse each file; compared per joint by name: OFFSETs, local translations and local rotations (angle
between the quaternions), and world positions (the project's forward kinematics against bvhio's readAsHierarchy +
loadPose + PositionWorld). Speed: the same files, both readers, in this process, per file the fastest of 3
interleaved runs. The writers write the motion each reader read; the files are read back with the project's reader
and their world positions compared with the original's. Unusual files: small texts of layouts that exporters write
(other channel orders, two rotation channels, lower-case channel names, Latin-1 names, braces on the name's line)
and broken files; each reader's outcome is recorded (positions against the project's where both read one; the
error otherwise).
Writes docs/results/dependencies/bvh_io.json.
"""

from __future__ import annotations

import argparse
import signal
import sys
import tempfile
import warnings
import zipfile
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import REPO, install_cost, max_abs, require, speed, write  # noqa: E402

from motiondiff.data.formats.bvh import read_bvh, write_bvh  # noqa: E402
from motiondiff.geometry.rotations import qangle  # noqa: E402

sys.path.insert(0, str(REPO / "tests" / "fixtures"))  # the tests' bvhio reader: world positions as bvhio computes them
from bvh_reader import bvhio_positions  # noqa: E402

DATA = REPO.parent / "shared" / "data" / "bandai-namco"

with warnings.catch_warnings():  # bvhio imports PyGLM as `glm`, which PyGLM plans to deprecate
    warnings.simplefilter("ignore", PendingDeprecationWarning)
    bvhio = require("bvhio")


# ---- the corpus ----------------------------------------------------------------------------------------------------
def extract(folder: Path, ds2_every: int) -> list[Path]:
    """ds1's clips and every ds2_every-th clip of ds2, extracted into `folder` (bvhio reads paths only)."""
    paths = []
    for name, every in (("bandai-ds1.zip", 1), ("bandai-ds2.zip", ds2_every)):
        with zipfile.ZipFile(DATA / name) as zf:
            members = sorted(m for m in zf.namelist() if m.lower().endswith(".bvh"))[::every]
            for member in members:
                target = folder / Path(member).name
                target.write_bytes(zf.read(member))
                paths.append(target)
    return paths


# ---- bvhio's view of a file -----------------------------------------------------------------------------------------
def bvhio_local(path: Path) -> dict:
    """Per joint name: OFFSET (3,), local translations (F, 3) and rotations (F, 4) (w, x, y, z) as bvhio reads them."""
    container = bvhio.readAsBvh(str(path))
    out = {}
    for joint, _, _ in container.Root.layout():
        out[joint.Name] = (
            np.array(tuple(joint.Offset)),
            np.array([tuple(k.Position) for k in joint.Keyframes]).reshape(-1, 3),
            np.array([(k.Rotation.w, k.Rotation.x, k.Rotation.y, k.Rotation.z) for k in joint.Keyframes]).reshape(
                -1, 4
            ),
        )
    return out


def compare_file(path: Path) -> dict:
    ours = read_bvh(path)
    theirs = bvhio_local(path)
    idx = {n: i for i, n in enumerate(ours.joint_names)}
    offsets = max(max_abs(ours.offsets[idx[n]], v[0]) for n, v in theirs.items())
    trans = max(max_abs(ours.translations[:, idx[n]], v[1]) for n, v in theirs.items())
    angle = max(float(np.degrees(qangle(ours.rotations[:, idx[n]], v[2])).max()) for n, v in theirs.items())
    world = max_abs(ours.positions(), bvhio_positions(path, ours.joint_names))
    return {"frames": ours.num_frames, "joints": ours.num_joints, "offset_cm": offsets, "translation_cm": trans,
            "rotation_deg": angle, "world_position_cm": world}  # fmt: skip


# ---- writers --------------------------------------------------------------------------------------------------------
def roundtrip(path: Path, folder: Path) -> dict:
    """Each writer writes what its reader read; world positions of the written file (read back by the project's
    reader) against the original's, and each write's time (the fastest of 3 interleaved)."""
    original = read_bvh(path)
    reference = original.positions()
    ours_path, theirs_path = folder / "ours.bvh", folder / "theirs.bvh"
    container = bvhio.readAsBvh(str(path))
    times = speed(
        lambda: write_bvh(ours_path, original), lambda: bvhio.writeBvh(str(theirs_path), container), repeats=3
    )
    ours_s, theirs_s = times["project_s"], times["library_s"]
    ours_back, theirs_back = read_bvh(ours_path), read_bvh(theirs_path)
    order = [theirs_back.joint_names.index(n) for n in original.joint_names]
    return {"project_write_s": ours_s, "bvhio_write_s": theirs_s,
            "project_roundtrip_cm": max_abs(ours_back.positions(), reference),
            "bvhio_roundtrip_cm": max_abs(theirs_back.positions()[:, order], reference),
            "bvhio_channels_kept": [tuple(c) for c in theirs_back.channels] == [tuple(c) for c in original.channels]}  # fmt: skip


# ---- unusual files --------------------------------------------------------------------------------------------------
def _bvh(
    root_channels: str, spine_channels: str, rows: list[str], spine_name: str = "Spine", brace: str = "\n  "
) -> str:
    """Hips -> Spine (the case's channels) -> Head (Z X Y rotations, 5 15 25 in every frame): the Spine's rotation
    moves the Head, so a reader that loses it shows in the world positions."""
    return (f"HIERARCHY\nROOT Hips\n{{\n  OFFSET 0 0 0\n  CHANNELS {root_channels}\n  JOINT {spine_name}{brace}{{\n"
            f"    OFFSET 0 10 0\n    CHANNELS {spine_channels}\n    JOINT Head\n    {{\n      OFFSET 0 10 0\n"
            "      CHANNELS 3 Zrotation Xrotation Yrotation\n      End Site\n      {\n        OFFSET 0 10 0\n      }\n"
            f"    }}\n  }}\n}}\nMOTION\nFrames: {len(rows)}\nFrame Time: 0.033333\n"
            + "\n".join(f"{r} 5 15 25" for r in rows) + "\n")  # fmt: skip


ROOT6 = "6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
CASES = {
    "standard ZXY": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation", ["1 90 2 10 20 30 40 50 60", "0 91 0 -5 5 80 1 2 3"]),
    "XYZ order everywhere": _bvh("6 Xposition Yposition Zposition Xrotation Yrotation Zrotation",
                                "3 Xrotation Yrotation Zrotation", ["1 90 2 10 20 30 40 50 60"]),
    "two rotation channels": _bvh(ROOT6, "2 Zrotation Xrotation", ["1 90 2 10 20 30 40 50"]),
    "position channels on a child": _bvh(ROOT6, "6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                                         ["1 90 2 10 20 30 0 12 0 40 50 60"]),
    "lower-case channel names": _bvh(ROOT6, "3 zrotation xrotation yrotation", ["1 90 2 10 20 30 40 50 60"]),
    "Latin-1 joint name": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation", ["1 90 2 10 20 30 40 50 60"],
                               spine_name="Rücken"),
    "brace on the name's line": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation", ["1 90 2 10 20 30 40 50 60"],
                                     brace=" "),
    "CRLF line ends": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation", ["1 90 2 10 20 30 40 50 60"]).replace("\n", "\r\n"),
    "broken: fewer frames than declared": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation",
                                               ["1 90 2 10 20 30 40 50 60"]).replace("Frames: 1", "Frames: 3"),
    "broken: a row with a missing value": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation",
                                               ["1 90 2 10 20 30 40 50 60", "1 90 2 10 20 30 40 50"]),
    "broken: a non-numeric value": _bvh(ROOT6, "3 Zrotation Xrotation Yrotation", ["1 90 2 10 20 30 40 abc 60"]),
    "broken: unknown channel name": _bvh(ROOT6, "3 Zrotation Xrotation Wrotation", ["1 90 2 10 20 30 40 50 60"]),
}  # fmt: skip


class _Timeout(Exception):
    pass


def _outcome(read, seconds: int = 5):
    """(result, None) or (None, 'ErrorType: message'); a read still going after `seconds` is stopped."""

    def alarm(*_):
        raise _Timeout(f"no answer after {seconds} s (stopped)")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        return read(), None
    except Exception as err:  # noqa: BLE001 (recording whatever each reader does)
        return None, f"{type(err).__name__}: {str(err).splitlines()[0][:160] if str(err) else ''}"
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def unusual_files(folder: Path) -> dict:
    results = {}
    for name, text in CASES.items():
        path = folder / "case.bvh"
        path.write_bytes(text.encode("latin-1") if "Rücken" in text else text.encode())
        ours, ours_err = _outcome(partial(read_bvh, path))
        names = ours.joint_names if ours else ["Hips", "Spine", "Head"]
        theirs, theirs_err = _outcome(partial(bvhio_positions, path, names))
        row = {"project": "read" if ours else ours_err, "bvhio": "read" if theirs is not None else theirs_err}
        if ours is not None and theirs is not None:
            row["world_position_difference"] = max_abs(ours.positions(), theirs)
        results[name] = row
    return results


# ---- main -----------------------------------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ds2-every", type=int, default=40, help="every k-th clip of bandai-ds2 (sorted names)")
    parser.add_argument("--time-files", type=int, default=20, help="files (every k-th of the corpus) timed")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        sys.exit(f"{DATA} not found: the comparison reads the Bandai Namco zips from ../shared/data")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        paths = extract(folder, args.ds2_every)
        per_file = {p.name: compare_file(p) for p in paths}
        keys = ("offset_cm", "translation_cm", "rotation_deg", "world_position_cm")
        faithfulness = {k: max(r[k] for r in per_file.values()) for k in keys}
        timed = paths[:: max(1, len(paths) // args.time_files)][: args.time_files]
        frames = sum(per_file[p.name]["frames"] for p in timed)
        names = {p: read_bvh(p).joint_names for p in timed}
        readers = {
            "read": (lambda p: read_bvh(p), lambda p: bvhio.readAsBvh(str(p))),
            "read_and_world_positions": (lambda p: read_bvh(p).positions(), lambda p: bvhio_positions(p, names[p])),
        }
        times = {}
        for label, (ours, theirs) in readers.items():
            rows = [speed(lambda: ours(p), lambda: theirs(p), repeats=3) for p in timed]  # noqa: B023
            times[f"project_{label}_s"] = sum(r["project_s"] for r in rows)
            times[f"bvhio_{label}_s"] = sum(r["library_s"] for r in rows)
        trips = [roundtrip(p, folder) for p in timed]
        writers = {
            "project_write_s": sum(t["project_write_s"] for t in trips),
            "bvhio_write_s": sum(t["bvhio_write_s"] for t in trips),
            "project_roundtrip_cm": max(t["project_roundtrip_cm"] for t in trips),
            "bvhio_roundtrip_cm": max(t["bvhio_roundtrip_cm"] for t in trips),
            "bvhio_keeps_every_channel_list": all(t["bvhio_channels_kept"] for t in trips),
        }
        cases = unusual_files(folder)
    result = {
        "corpus": {
            "files": len(paths),
            "frames": sum(r["frames"] for r in per_file.values()),
            "source": f"bandai-ds1 (all), bandai-ds2 (every {args.ds2_every}th)",
        },  # fmt: skip
        "faithfulness_max_over_corpus": faithfulness,
        "speed": {
            "files": len(timed),
            "frames": frames,
            **times,
            "read_bvhio_over_project": times["bvhio_read_s"] / times["project_read_s"],
            "positions_bvhio_over_project": times["bvhio_read_and_world_positions_s"]
            / times["project_read_and_world_positions_s"],
            "how": "per file the fastest of 3 interleaved runs, summed over the files",
        },  # fmt: skip
        "writers": {**writers, "write_bvhio_over_project": writers["bvhio_write_s"] / writers["project_write_s"]},
        "unusual_files": cases,
        "size": install_cost("bvhio"),
        "per_file": per_file,
    }
    write("bvh_io", result)
    print({k: result[k] for k in ("corpus", "faithfulness_max_over_corpus", "speed", "writers")})
    for name, row in cases.items():
        print(f"  {name}: {row}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
