"""Property-based fuzzing of every reader.

Each reader starts from a real file of ``../shared/data`` (a short prefix of it, so one example is cheap) and
hypothesis mutates it: byte flips, truncation, deleted and duplicated lines, numbers replaced by huge, negative,
NaN or infinite values, unicode garbage, a ``Frames:`` count of 10^9; the npz formats also get array-level
mutations (NaN/inf, wrong shapes and dtypes, missing keys, absurd frame rates). The rule: ``load_motion`` returns
a valid motion or raises :class:`InputError`; never another exception, never more than 2 s of CPU or 200 MB of
allocations for one case.

Profiles (tests/conftest.py): ``ci`` (the default, 200 examples per reader, derandomised: every run tries the
same cases) and ``fuzz`` (10,000 per reader: ``make fuzz``). Cases the fuzzer found are kept as regular tests in
tests/test_fuzz_found.py.
"""

from __future__ import annotations

import io
import json
import re
import shutil
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motion2video.core.errors import InputError
from motion2video.formats.io import load_motion
from motion2video.core.motion import FaceMotion, Motion

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
MAX_CPU_S = 2.0
MAX_BYTES = 200 * 2**20
NUMBER = re.compile(rb"-?\d+\.?\d*(?:[eE][-+]?\d+)?")
BAD_NUMBERS = [b"nan", b"inf", b"-inf", b"1e308", b"-1e308", b"-1", b"0", b"1e999", b"999999999999", b"-7",
               b"NaN", b"1.#IND", b""]
FRAME_COUNTS = [b"1000000000", b"-5", b"0", b"abc", b"99999999999999999999999", b"1e9"]

# --- seeds: prefixes of real files, in the folder layout their readers expect --------------------------------


def _lines_prefix(path: Path, lines: int) -> bytes:
    with open(path, "rb") as f:
        return b"".join(f.readline() for _ in range(lines))


def _bvh_seed() -> bytes:
    """The hierarchy of a real CMU BVH and its first 12 frames (``Frames:`` set to match)."""
    text = (SHARED / "mocap" / "cmu" / "02_03.bvh").read_bytes()
    head, motion = text.split(b"MOTION", 1)
    lines = motion.strip().splitlines()
    frame_time = next(line for line in lines if line.lower().startswith(b"frame time"))
    data = lines[lines.index(frame_time) + 1:][:12]
    return head + b"MOTION\nFrames: 12\n" + frame_time + b"\n" + b"\n".join(data) + b"\n"


def _deepmimic_seed() -> bytes:
    """The first 8 frames of a real DeepMimic motion file, still valid JSON."""
    record = json.loads((SHARED / "mocap" / "deepmimic" / "txt" / "humanoid3d_backflip.txt").read_text())
    record["Frames"] = record["Frames"][:8]
    return json.dumps(record, indent=0).encode()


READERS = {
    # name: (file name in the fuzz folder, seed bytes, extra files copied beside it {relative path: source})
    "bvh": ("clip.bvh", _bvh_seed, {}),
    "face_csv": ("capture.csv", lambda: _lines_prefix(SHARED / "face" / "llv" / "dao.csv", 16), {}),
    "deepmimic": ("deepmimic/txt/clip.txt", _deepmimic_seed,
                  {"deepmimic/humanoid3d_character.txt": SHARED / "mocap" / "deepmimic" / "humanoid3d_character.txt"}),
    "expmap": ("cmu-bench/test/jumping/clip.txt",
               lambda: _lines_prefix(SHARED / "mocap" / "cmu-bench" / "test" / "jumping" / "jumping_1.txt", 12),
               {"cmu-bench/skeleton.json": SHARED / "mocap" / "cmu-bench" / "skeleton.json"}),
}


@pytest.fixture(scope="module")
def fuzz_root(tmp_path_factory) -> Path:
    if not SHARED.is_dir():
        pytest.fail(f"shared data directory missing: {SHARED}")
    return tmp_path_factory.mktemp("fuzz")


def _check_one(path: Path) -> None:
    """The rule, for one mutated file."""
    tracemalloc.start()
    start = time.process_time()
    try:
        motion = load_motion(path)
    except InputError as err:
        assert "\n" not in str(err)
        motion = None
    finally:
        cpu = time.process_time() - start
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    assert cpu <= MAX_CPU_S, f"{cpu:.2f} s of CPU for one case"
    assert peak <= MAX_BYTES, f"{peak / 2**20:.0f} MB allocated for one case"
    if motion is not None:
        assert isinstance(motion, (Motion, FaceMotion))
        data = motion.joints if isinstance(motion, Motion) else motion.params
        assert np.isfinite(data).all() and motion.fps > 0 and motion.num_frames >= 1


# --- byte / line mutations of the text formats ----------------------------------------------------------

def _mutations(seed_len: int):
    pos = st.integers(0, max(0, seed_len - 1))
    return st.lists(st.one_of(
        st.tuples(st.just("flip"), pos, st.integers(1, 255)),
        st.tuples(st.just("truncate"), pos),
        st.tuples(st.just("delete_line"), st.integers(0, 400)),
        st.tuples(st.just("dup_line"), st.integers(0, 400), st.integers(1, 50)),
        st.tuples(st.just("number"), st.integers(0, 2000), st.sampled_from(BAD_NUMBERS)),
        st.tuples(st.just("garbage"), pos, st.text(min_size=1, max_size=24)),
        st.tuples(st.just("frames"), st.sampled_from(FRAME_COUNTS)),
    ), min_size=1, max_size=4)


def mutate(data: bytes, ops) -> bytes:
    for op in ops:
        kind = op[0]
        if kind == "flip" and data:
            i = op[1] % len(data)
            data = data[:i] + bytes([data[i] ^ op[2]]) + data[i + 1:]
        elif kind == "truncate":
            data = data[: op[1]]
        elif kind in ("delete_line", "dup_line"):
            lines = data.splitlines(keepends=True)
            if lines:
                i = op[1] % len(lines)
                lines[i:i + 1] = [] if kind == "delete_line" else [lines[i]] * op[2]
                data = b"".join(lines)
        elif kind == "number":
            numbers = list(NUMBER.finditer(data))
            if numbers:
                m = numbers[op[1] % len(numbers)]
                data = data[: m.start()] + op[2] + data[m.end():]
        elif kind == "garbage":
            i = min(op[1], len(data))
            data = data[:i] + op[2].encode("utf-8", "surrogatepass") + data[i:]
        elif kind == "frames":
            data = re.sub(rb"Frames:\s*\S+", b"Frames: " + op[1], data, count=1)
    return data


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(data=st.data())
@pytest.mark.parametrize("reader", sorted(READERS))
def test_text_readers(reader, data, fuzz_root):
    name, seed_of, extra = READERS[reader]
    seed = _SEEDS.setdefault(reader, seed_of())
    folder = fuzz_root / reader
    for rel, src in extra.items():
        target = folder / rel
        if not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(src, target)
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if reader not in _WARM:  # the reader's first call imports what it needs: not the case's own cost
        path.write_bytes(seed)
        _WARM[reader] = load_motion(path).num_frames
    path.write_bytes(mutate(seed, data.draw(_mutations(len(seed)), label="mutations")))
    _check_one(path)


_SEEDS: dict[str, bytes] = {}
_WARM: dict[str, int] = {}


def test_seeds_are_valid(fuzz_root):
    """Unmutated, every seed reads: the fuzzing starts from real, readable files."""
    for reader, (name, seed_of, extra) in READERS.items():
        folder = fuzz_root / f"seed-{reader}"
        for rel, src in extra.items():
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(src, folder / rel)
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(seed_of())
        motion = load_motion(path)
        assert motion.num_frames >= 8, reader


# --- array mutations of the npz formats ------------------------------------------------------------------

def _real_joints() -> np.ndarray:
    return load_motion(SHARED / "mocap" / "cmu" / "02_03.bvh").joints[:10].astype(np.float32)  # (10, 17, 3)


def _npz_seeds() -> dict[str, dict]:
    from motion2video.formats.face_csv import load_face_csv
    from motion2video.core.skeletons import H36M_32_TO_17

    joints = _real_joints()
    face = load_face_csv(SHARED / "face" / "llv" / "dao.csv")
    positions = np.zeros((10, 32, 3))
    positions[:, list(H36M_32_TO_17)] = joints
    return {
        "body_npz": {"joints": joints, "fps": np.float64(25.0), "skeleton": np.str_("h36m-17")},
        "face_npz": {"face": face.params[:10].astype(np.float32), "fps": np.float64(face.fps),
                     "identity": np.str_("{}")},
        "videopose3d": {"positions_3d": {"S1": {"Walking": positions}}},
    }


ARRAY_VALUES = st.sampled_from(["nan", "inf", "empty", "drop_axis", "add_axis", "wrong_width", "strings",
                                "huge", "negative", "zero", "object", "scalar", "missing", "bool"])


def _mutate_array(value, how: str, rng: np.random.Generator):
    """One array-level mutation of ``value`` (a mutation that does not apply to this array returns it as is)."""
    try:
        return _mutated(value, how, rng)
    except ValueError:  # e.g. reshaping an empty array
        return value


def _mutated(value, how: str, rng: np.random.Generator):
    if isinstance(value, dict) or how == "missing":
        return value
    a = np.asarray(value)
    if a.dtype.kind in "US" and how not in ("strings", "scalar", "object"):
        return np.str_(["", "h36m-32", "\x00garbage\u2603", "x" * 10000][rng.integers(4)])
    if how == "nan" and a.size and a.dtype.kind == "f":
        a = a.copy()
        a.flat[rng.integers(a.size)] = np.nan
    elif how == "inf" and a.size and a.dtype.kind == "f":
        a = a.copy()
        a.flat[rng.integers(a.size)] = -np.inf
    elif how == "empty":
        a = a.reshape(-1)[:0]
    elif how == "drop_axis" and a.ndim > 1:
        a = a.reshape(a.shape[0], -1)
    elif how == "drop_axis" and a.ndim == 1 and a.size:
        a = a[:1].reshape(())
    elif how == "add_axis":
        a = a[None]
    elif how == "wrong_width" and a.ndim >= 2:
        a = a[..., :-1]
    elif how == "strings":
        a = a.astype(str)
    elif how == "huge":
        with np.errstate(over="ignore"):  # float32 * 1e300 is inf: one of the values wanted here
            a = a * 1e300 if a.dtype.kind == "f" else np.float64(1e300)
    elif how == "negative":
        a = -np.abs(a) - 1 if a.dtype.kind in "fi" else a
    elif how == "zero":
        a = np.zeros_like(a)
    elif how == "object":
        a = np.array([None, 1], dtype=object)
    elif how == "scalar":
        a = np.float64(7.0)
    elif how == "bool":
        a = a.astype(bool)
    return a


def _write_npz(path: Path, arrays: dict) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(ops=st.lists(st.tuples(st.integers(0, 10), ARRAY_VALUES, st.integers(0, 2**32 - 1)), min_size=1, max_size=3),
       extra_key=st.booleans(), byte_ops=st.lists(st.tuples(st.sampled_from(["flip", "truncate"]),
                                                             st.integers(0, 10**6), st.integers(1, 255)), max_size=2))
@pytest.mark.parametrize("reader", ["body_npz", "face_npz", "videopose3d"])
def test_npz_readers(reader, ops, extra_key, byte_ops, fuzz_root):
    seed = dict(_NPZ_SEEDS.setdefault("all", _npz_seeds())[reader])
    for index, how, salt in ops:
        if not seed:
            break
        key = sorted(seed)[index % len(seed)]
        rng = np.random.default_rng(salt)
        if how == "missing":
            seed.pop(key)
        elif reader == "videopose3d" and isinstance(seed[key], dict):
            clips = {"S1": {"Walking": _mutate_array(seed[key]["S1"]["Walking"], how, rng)}}
            seed[key] = clips if how != "object" else np.array([clips, 3], dtype=object)
        else:
            seed[key] = _mutate_array(seed[key], how, rng)
    if extra_key:
        seed["unexpected"] = np.arange(3)
    if not seed:
        seed["nothing"] = np.zeros(1)
    path = fuzz_root / f"{reader}.npz"
    _write_npz(path, seed)
    data = path.read_bytes()
    for kind, at, value in byte_ops:
        data = mutate(data, [("flip", at % max(1, len(data)), value)] if kind == "flip" else [("truncate", at % max(1, len(data)))])
    path.write_bytes(data)
    _check_one(path)


_NPZ_SEEDS: dict[str, dict] = {}


def test_npz_seeds_are_valid(fuzz_root):
    for reader, arrays in _npz_seeds().items():
        path = fuzz_root / f"seed-{reader}.npz"
        _write_npz(path, arrays)
        assert load_motion(path).num_frames == 10, reader


# --- OpenPose: a folder of per-frame JSON files ----------------------------------------------------------

def _openpose_seed_frames() -> list[bytes]:
    """Per-frame OpenPose (COCO-18) JSON of a real clip, projected to pixels (x right, y down)."""
    joints = _real_joints()  # (10, 17, 3) metres, z up
    frames = []
    for t in range(len(joints)):
        xy = np.stack([300 + 150 * joints[t, :, 0], 400 - 150 * joints[t, :, 2]], axis=1)
        keypoints = np.concatenate([xy, np.full((17, 1), 0.9)], axis=1)
        keypoints = np.concatenate([keypoints, [[xy[0, 0], xy[0, 1], 0.9]]])  # 18 keypoints
        people = [{"person_id": [-1], "pose_keypoints_2d": keypoints.reshape(-1).round(3).tolist()}]
        frames.append(json.dumps({"version": 1.3, "people": people}).encode())
    return frames


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(which=st.integers(0, 9), data=st.data())
def test_openpose_reader(which, data, fuzz_root):
    folder = fuzz_root / "openpose"
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir()
    frames = _openpose_seed_frames()
    frames[which] = mutate(frames[which], data.draw(_mutations(len(frames[which])), label="mutations"))
    for t, payload in enumerate(frames):
        (folder / f"clip_{t:012d}_keypoints.json").write_bytes(payload)
    _check_one(folder)


def test_openpose_seed_is_valid(fuzz_root):
    folder = fuzz_root / "seed-openpose"
    folder.mkdir()
    for t, payload in enumerate(_openpose_seed_frames()):
        (folder / f"clip_{t:012d}_keypoints.json").write_bytes(payload)
    assert load_motion(folder).num_frames == 10
