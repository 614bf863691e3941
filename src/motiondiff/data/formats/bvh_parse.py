"""BVH text -> hierarchy and raw channel values (the syntax half of `motiondiff.data.formats.bvh`).

Kept apart from the rotation handling so each half stays small. Every problem raises `BVHError` with the
source name, the line number where one applies, what is wrong and how to fix it.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field

import numpy as np

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
VALID_CHANNELS = POSITION_CHANNELS + ROTATION_CHANNELS
_CHANNEL_KINDS = {name.lower(): (name[1:], "XYZ".index(name[0])) for name in VALID_CHANNELS}
# What a file may ask for (a few KB must not ask for GiBs): seconds per frame, frames, values.
MIN_FRAME_TIME, MAX_FRAME_TIME = 1e-4, 10.0  # 10,000 fps .. one frame every 10 s
MAX_FRAMES = 500_000  # over 4 hours at 30 fps
MAX_VALUES = 30_000_000  # frames x channels (240 MB of float64)
MAX_JOINTS, MAX_DEPTH = 10_000, 200  # joints of a skeleton, and how deep they nest
MAX_FRAME_JOINTS = 10_000_000  # frames x joints: each becomes a rotation and a translation (560 MB of float64)


class BVHError(ValueError):
    """A BVH file (or text) that cannot be read; the message names the file, line, problem and fix."""


def bvh_error(source: str, line: int | None, problem: str, fix: str) -> BVHError:
    where = f"{source}: line {line}" if line is not None else source
    return BVHError(f"{where}: {problem}; {fix}")


def channel_kind(name: str) -> tuple[str, int]:
    """'Zrotation' -> ('rotation', 2). Case-insensitive, as some exporters write 'XROTATION'."""
    return _CHANNEL_KINDS[name.lower()]


@dataclass
class RawBVH:
    """What the file says, before any rotation math: the hierarchy and the (frames, channels) value table."""

    names: list[str] = field(default_factory=list)
    parents: list[int] = field(default_factory=list)
    offsets: list[np.ndarray | None] = field(default_factory=list)
    channels: list[tuple[str, ...]] = field(default_factory=list)
    end_sites: dict[int, np.ndarray] = field(default_factory=dict)
    frame_time: float = 0.0
    values: np.ndarray | None = None
    depth: list[int] = field(default_factory=list, repr=False)  # nesting depth of each joint (the root: 0)
    seen: set[str] = field(default_factory=set, repr=False)  # the names so far


class _Tokens:
    """Hierarchy tokens with their line numbers. Braces are split off words ('Hips{' -> 'Hips', '{')."""

    def __init__(self, text: str, source: str):
        self.source = source
        self.items = [
            (tok, n) for n, line in enumerate(text.split("\n"), 1) for tok in re.findall(r"[{}]|[^\s{}]+", line)
        ]
        self.pos = 0

    def done(self) -> bool:
        return self.pos >= len(self.items)

    def next(self, expecting: str, opened: int | None = None) -> tuple[str, int]:
        if self.done():
            last = self.items[-1][1] if self.items else None
            where = f" (opened at line {opened})" if opened else ""
            raise bvh_error(
                self.source,
                last,
                f"the hierarchy ends while expecting {expecting}{where}",
                "the brace structure is incomplete or the file is cut; add the missing '}' or re-export it",
            )
        self.pos += 1
        return self.items[self.pos - 1]

    def rest_of_line(self, line: int) -> list[str]:
        """Tokens left on `line`, stopping before a '{' (joint names may contain spaces)."""
        out = []
        while not self.done() and self.items[self.pos][1] == line and self.items[self.pos][0] != "{":
            out.append(self.items[self.pos][0])
            self.pos += 1
        return out

    def numbers(self, count: int, what: str, line: int) -> np.ndarray:
        toks = self.rest_of_line(line)
        if len(toks) != count:
            raise bvh_error(
                self.source, line, f"{what} needs {count} numbers, found {toks}", "write e.g. 'OFFSET 0 1 0'"
            )
        try:
            vals = np.array([float(t) for t in toks])
        except ValueError:
            raise bvh_error(self.source, line, f"{what} has a non-numeric value in {toks}", "fix the number") from None
        if not np.isfinite(vals).all():
            raise bvh_error(self.source, line, f"{what} holds NaN or Inf: {toks}", "write finite numbers")
        return vals


def parse_text(text: str, source: str) -> RawBVH:
    text = text.lstrip("\ufeff").replace("\r\n", "\n").replace("\r", "\n")
    if not text.strip():
        raise bvh_error(source, None, "the file is empty", "re-export or re-download it")
    motion = re.search(r"^[ \t]*MOTION\b", text, re.M)
    raw = RawBVH()
    _parse_hierarchy(_Tokens(text if motion is None else text[: motion.start()], source), raw)
    if motion is None:  # _parse_hierarchy raised if anything followed the root, so the file just stops here
        raise bvh_error(
            source,
            None,
            "no MOTION section after the hierarchy",
            "the file is truncated or holds only a skeleton; re-export it with its motion",
        )
    first_line = text.count("\n", 0, motion.start()) + 1
    _parse_motion(text, motion.start(), source, first_line, raw)  # (no copy of a large text)
    return raw


def _parse_hierarchy(toks: _Tokens, raw: RawBVH) -> None:
    tok, line = toks.next("HIERARCHY")
    if tok.upper() != "HIERARCHY":
        raise bvh_error(
            toks.source,
            line,
            f"expected HIERARCHY as the first word, found {tok!r}",
            "a BVH file starts with 'HIERARCHY' then 'ROOT <name>'; check that this is a BVH file",
        )
    tok, line = toks.next("ROOT <name>")
    if tok.upper() != "ROOT":
        raise bvh_error(toks.source, line, f"expected 'ROOT <name>' after HIERARCHY, found {tok!r}", "add the ROOT")
    _parse_joint(toks, raw, -1, line)
    if not toks.done():
        tok, line = toks.next("MOTION")
        if tok.upper() == "ROOT":
            raise bvh_error(
                toks.source,
                line,
                "a second ROOT: files with several skeletons are not supported",
                "split the file into one file per skeleton",
            )
        problem = "more '}' than '{'" if tok == "}" else f"expected MOTION after the hierarchy, found {tok!r}"
        raise bvh_error(toks.source, line, problem, "check the brace structure and the MOTION line")


def _parse_joint(toks: _Tokens, raw: RawBVH, parent: int, line: int) -> None:
    name = " ".join(toks.rest_of_line(line))
    if not name:
        raise bvh_error(toks.source, line, "ROOT/JOINT without a name", "write e.g. 'JOINT LeftArm'")
    depth = raw.depth[parent] + 1 if parent >= 0 else 0
    if len(raw.names) >= MAX_JOINTS or depth > MAX_DEPTH:
        raise bvh_error(
            toks.source,
            line,
            f"more than {MAX_JOINTS} joints, or joints nested more than {MAX_DEPTH} deep",
            "this is not a skeleton this reader takes; check the file or export the skeleton without extra joints",
        )
    if name in raw.seen:
        raise bvh_error(
            toks.source,
            line,
            f"joint name {name!r} appears twice (joints are found by name, so one would stand for the other)",
            "rename one of them in the file (e.g. with a suffix) and export it again",
        )
    j = len(raw.names)
    raw.seen.add(name)
    raw.depth.append(depth)
    raw.names.append(name)
    raw.parents.append(parent)
    raw.offsets.append(None)
    raw.channels.append(())
    _expect_open(toks, f"joint {name!r}")
    while True:
        tok, at = toks.next(f"'}}' closing joint {name!r}", opened=line)
        key = tok.upper()
        if tok == "}":
            break
        if key == "OFFSET":
            raw.offsets[j] = toks.numbers(3, f"OFFSET of joint {name!r}", at)
        elif key == "CHANNELS":
            raw.channels[j] = _parse_channels(toks, at)
        elif key == "JOINT":
            _parse_joint(toks, raw, j, at)
        elif key == "END":
            toks.rest_of_line(at)  # 'Site' (or a name some exporters put there)
            _expect_open(toks, "End Site")
            off, at = toks.next("OFFSET of the End Site")
            if off.upper() != "OFFSET":
                raise bvh_error(toks.source, at, f"End Site needs an OFFSET, found {off!r}", "add 'OFFSET x y z'")
            site = toks.numbers(3, f"End Site OFFSET of joint {name!r}", at)
            raw.end_sites.setdefault(j, site)  # a second End Site on one joint is rare; the first one is kept
            tok, at = toks.next("'}' closing the End Site", opened=at)
            if tok != "}":
                raise bvh_error(toks.source, at, f"expected '}}' closing the End Site, found {tok!r}", "add the '}'")
        else:
            raise bvh_error(
                toks.source,
                at,
                f"unexpected {tok!r} inside joint {name!r}",
                "a joint holds OFFSET, CHANNELS, JOINT, End Site and '}'; check the brace structure",
            )
    if raw.offsets[j] is None:
        raise bvh_error(toks.source, line, f"joint {name!r} has no OFFSET", "add 'OFFSET x y z' to the joint")


def _expect_open(toks: _Tokens, what: str) -> None:
    tok, at = toks.next(f"'{{' opening {what}")
    if tok != "{":
        raise bvh_error(toks.source, at, f"expected '{{' opening {what}, found {tok!r}", "check the brace structure")


def _parse_channels(toks: _Tokens, line: int) -> tuple[str, ...]:
    words = toks.rest_of_line(line)
    if not words or not words[0].isdigit():
        raise bvh_error(
            toks.source,
            line,
            "CHANNELS needs a count then the names",
            "write e.g. 'CHANNELS 3 Zrotation ...'",
        )
    count, names = int(words[0]), tuple(words[1:])
    if len(names) != count:
        raise bvh_error(
            toks.source,
            line,
            f"CHANNELS says {count} channels but lists {len(names)}: {' '.join(names)}",
            "make the count match the names (all on the CHANNELS line)",
        )
    for ch in names:
        if ch.lower() not in _CHANNEL_KINDS:
            raise bvh_error(
                toks.source,
                line,
                f"unknown channel {ch!r}",
                f"valid channel names are {', '.join(VALID_CHANNELS)}",
            )
    if len({n.lower() for n in names}) != len(names):
        raise bvh_error(toks.source, line, f"a channel appears twice in {' '.join(names)}", "list each channel once")
    return names


def _next_line(text: str, pos: int, line: int) -> tuple[str, int, int]:
    """The next non-blank line from pos -> (line text, position after it, its line number)."""
    while pos < len(text):
        end = text.find("\n", pos)
        end = len(text) if end < 0 else end
        if text[pos:end].strip():
            return text[pos:end].strip(), end + 1, line
        pos, line = end + 1, line + 1
    return "", pos, line


def _parse_motion(text: str, start: int, source: str, first_line: int, raw: RawBVH) -> None:
    _, pos, line = _next_line(text, start, first_line)  # the MOTION line itself
    frames_line, pos, line = _next_line(text, pos, line + 1)
    m = re.fullmatch(r"Frames\s*:\s*(\d+)", frames_line, re.I)
    if m is None:
        raise bvh_error(source, line, f"expected 'Frames: <count>' after MOTION, found {frames_line!r}", "fix it")
    frames = int(m.group(1))
    width, joints = sum(len(c) for c in raw.channels), len(raw.names)
    if frames > MAX_FRAMES or frames * width > MAX_VALUES or frames * joints > MAX_FRAME_JOINTS:
        raise bvh_error(
            source,
            line,
            f"'Frames: {frames}' x {width} channels x {joints} joints is more than this reader takes ({MAX_FRAMES} "
            f"frames, {MAX_VALUES} values, {MAX_FRAME_JOINTS} frames x joints)",
            "split the capture into shorter files",
        )
    time_line, pos, line = _next_line(text, pos, line + 1)
    m = re.fullmatch(r"Frame\s*Time\s*:\s*(\S+)", time_line, re.I)
    try:
        frame_time = float(m.group(1)) if m else None
    except ValueError:
        frame_time = None
    if frame_time is None or not np.isfinite(frame_time) or frame_time <= 0:
        raise bvh_error(
            source,
            line,
            f"expected 'Frame Time: <seconds>' with a positive number, found {time_line!r}",
            "write the seconds per frame, e.g. 'Frame Time: 0.0333333' for 30 fps",
        )
    if not MIN_FRAME_TIME <= frame_time <= MAX_FRAME_TIME:
        raise bvh_error(
            source,
            line,
            f"'Frame Time: {frame_time:g}' seconds per frame is outside {MIN_FRAME_TIME:g}..{MAX_FRAME_TIME:g} s",
            "write the seconds per frame (1 / fps, e.g. 0.0333333 for 30 fps), not the frame rate or a duration",
        )
    raw.frame_time = frame_time
    raw.values = _parse_values(text[pos:], source, line + 1, frames, width)


def _parse_values(data: str, source: str, first_line: int, frames: int, width: int) -> np.ndarray:
    """The (frames, width) value table, parsed in C without a Python list of tokens; the slow search for a bad
    token runs only on errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # numpy's "could not be read to its end" -> ValueError
        try:  # (numpy reads a string of only whitespace as [-1.0])
            values = np.fromstring(data, dtype=np.float64, sep=" ") if re.search(r"\S", data) else np.zeros(0)
        except ValueError:
            values = None
    if values is None:
        bad, token = next(((i, t) for i, t in _tokens(data) if not _is_float(t)), (0, data.split(None, 1)[0]))
        raise bvh_error(
            source,
            _token_line(data, bad, first_line),
            f"non-numeric value {token[:40]!r} in the MOTION data",
            "every value after 'Frame Time' must be a number; fix or re-export the file",
        )
    if values.size != frames * width:
        raise bvh_error(source, None, *_count_problem(frames, width, values.size))
    finite = np.isfinite(values)
    if not finite.all():
        bad = int(np.argmin(finite))
        raise bvh_error(
            source,
            _token_line(data, bad, first_line),
            f"{next(t for i, t in _tokens(data) if i == bad)[:40]!r} (NaN or Inf) in the MOTION data",
            "the exporter wrote an invalid number; re-export the clip or drop the frame",
        )
    return values.reshape(frames, width)


def _tokens(data: str):
    """(index, token) of the whitespace-separated tokens of `data`, one at a time (error path only)."""
    return ((i, m.group()) for i, m in enumerate(re.finditer(r"\S+", data)))


def _count_problem(frames: int, width: int, found: int) -> tuple[str, str]:
    expected = f"expected {frames} frames x {width} channels = {frames * width} values after MOTION, found {found}"
    if width == 0:
        return expected, "a skeleton without channels has no values; remove them"
    whole = found // width
    if found < frames * width:
        return (
            f"{expected}: the file is truncated ({whole} whole frames)",
            "re-export it or download it again",
        )
    return (
        f"{expected}: more values than 'Frames: {frames}' declares ({found / width:g} frames)",
        f"fix the Frames line (e.g. 'Frames: {whole}') or re-export the file",
    )


def _is_float(token: str) -> bool:
    """Whether numpy reads `token` as a number (Python's float also takes '1_000')."""
    try:
        np.float64(token)
    except ValueError:
        return False
    return "_" not in token


def _token_line(data: str, index: int, first_line: int) -> int:
    """Line number of the index-th whitespace-separated token of `data` (error path only)."""
    for i, m in enumerate(re.finditer(r"\S+", data)):
        if i == index:
            return first_line + data.count("\n", 0, m.start())
    return first_line
