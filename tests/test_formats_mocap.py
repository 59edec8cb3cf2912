"""The DeepMimic and exp-map readers: known answers, skeletons and layouts as data, bad files, and the
dispatch of load_motion over every kind of file in ../shared/data/mocap."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from motion2video.core.errors import InputError
from motion2video.formats import bvh, deepmimic, expmap
from motion2video.formats.mocap import load_mocap, mocap_kind
from motion2video.formats.io import load_motion

DEEPMIMIC_TWINS = sorted(p.stem for p in (Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
                                          / "deepmimic" / "txt").glob("*.txt"))


@pytest.fixture(scope="module")
def character(mocap_dir) -> deepmimic.Character:
    return deepmimic.read_character(mocap_dir / "deepmimic" / "humanoid3d_character.txt")


@pytest.fixture(scope="module")
def layout(mocap_dir) -> expmap.ExpmapLayout:
    return expmap.read_expmap_layout(mocap_dir / "cmu-bench" / "skeleton.json")


def test_there_are_15_known_answer_pairs():
    assert len(DEEPMIMIC_TWINS) == 15


@pytest.mark.parametrize("stem", DEEPMIMIC_TWINS)
def test_deepmimic_file_gives_the_joints_of_its_bvh_twin(mocap_dir, character, stem):
    """deepmimic/txt/X.txt is the original of deepmimic/X.bvh: every canonical joint of every frame agrees
    (the README measured at most 2.4e-7 m; the target is 1 cm)."""
    clip = deepmimic.read_deepmimic(mocap_dir / "deepmimic" / "txt" / f"{stem}.txt", character)
    mine = deepmimic.deepmimic_canonical(clip, character)
    twin = bvh.canonical_positions(bvh.read_bvh(mocap_dir / "deepmimic" / f"{stem}.bvh"))
    assert mine.joints.shape == twin.joints.shape
    assert np.abs(mine.joints - twin.joints).max() < 1e-5
    assert mine.fps == twin.fps  # 1 / frame duration = the BVH's frame time
    # The whole pipeline (floor, manifest rate) agrees too.
    a = load_motion(mocap_dir / "deepmimic" / "txt" / f"{stem}.txt")
    b = load_motion(mocap_dir / "deepmimic" / f"{stem}.bvh")
    np.testing.assert_allclose(a.joints, b.joints, atol=1e-5)


def test_character_file_is_data(mocap_dir, tmp_path, character):
    """A different character file plugs in: the same motion on a humanoid with 20% longer shins moves its
    knees and ankles apart by exactly that much."""
    data = json.loads((mocap_dir / "deepmimic" / "humanoid3d_character.txt").read_text())
    for joint in data["Skeleton"]["Joints"]:
        if joint["Name"].endswith("_ankle"):
            joint["AttachY"] *= 1.2
    (tmp_path / "long_shins.txt").write_text(json.dumps(data))
    motion = mocap_dir / "deepmimic-cmu" / "07_03.txt"
    normal = deepmimic.load_deepmimic(motion)
    long = deepmimic.load_deepmimic(motion, character=tmp_path / "long_shins.txt")
    shin = lambda m: np.linalg.norm(m.joints[:, 2] - m.joints[:, 3], axis=-1)  # noqa: E731 right knee-ankle
    np.testing.assert_allclose(shin(long), 1.2 * shin(normal), rtol=1e-5)
    np.testing.assert_allclose(shin(normal), 0.40987, rtol=1e-5)
    # A character whose joints do not fit the frames is named in the error.
    del data["Skeleton"]["Joints"][2]  # neck
    for joint in data["Skeleton"]["Joints"]:
        joint["Parent"] = joint["Parent"] - (joint["Parent"] > 2)
    (tmp_path / "no_neck.txt").write_text(json.dumps(data))
    with pytest.raises(InputError, match="lacks the joint"):
        deepmimic.read_character(tmp_path / "no_neck.txt")


def test_exp_map_layout_is_data(mocap_dir, tmp_path, layout):
    """Another column layout plugs in as data: the same motion written with the root position at the end of
    each line and in centimetres, described by its own skeleton.json, reads back to the same joints."""
    src = mocap_dir / "cmu-bench" / "test" / "soccer" / "soccer_1.txt"
    values = np.loadtxt(src, delimiter=",")  # (T + 1, 117)
    to_cm = layout.unit * 100.0
    moved = np.concatenate([values[:, 3:], values[:, :3] * to_cm], axis=1)
    folder = tmp_path / "other"
    folder.mkdir()
    np.savetxt(folder / "clip.txt", moved, delimiter=",", fmt="%.10g")
    spec = json.loads((mocap_dir / "cmu-bench" / "skeleton.json").read_text())
    spec["root_position_columns"] = [114, 115, 116]
    spec["expmap_columns"] = [[c - 3 for c in cols] for cols in spec["expmap_columns"]]
    spec["metres_per_unit"] = 0.01
    spec["offsets"] = [[to_cm * v for v in o] for o in spec["offsets"]]
    spec["fps"] = 60  # a layout's own rate applies without a manifest
    (folder / "skeleton.json").write_text(json.dumps(spec))
    a = load_motion(src)
    b = load_motion(folder / "clip.txt")
    assert mocap_kind(folder / "clip.txt") == "expmap" and b.fps == 60.0 and a.fps == 120.0
    np.testing.assert_allclose(b.joints, a.joints, atol=1e-5)


def test_exp_map_forward_kinematics_by_hand(layout):
    """Row-vector FK (R_i = E(e_i) R_parent, p_i = o_i R_parent + p_parent) on two frames: the rest pose
    stacks offsets; rotating the root by 90 degrees about y turns a +z offset into -x."""
    values = np.zeros((2, layout.values_per_frame))
    values[:, :3] = [1.0, 2.0, 3.0]
    values[1, 3:6] = [0.0, np.pi / 2, 0.0]
    pos = expmap.expmap_world_positions(values, layout)  # (2, 38, 3)
    chain = [6, 5, 4, 3, 2, 1, 0]  # left toe end up to the root
    rest = np.array([1.0, 2.0, 3.0]) + layout.offsets[chain].sum(axis=0)
    np.testing.assert_allclose(pos[0, 6], rest, atol=1e-9)
    # Frame 1: p = o R with R = E((0, pi/2, 0)); a row vector (0, 0, 1) times Ry(90) is (-1, 0, 0) (Ry(90)
    # as a column-vector matrix maps z to x; as row vectors, the transpose maps z to -x).
    rot = pos[1] - np.array([1.0, 2.0, 3.0])
    off = pos[0] - np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(rot[:, 0], -off[:, 2], atol=1e-9)
    np.testing.assert_allclose(rot[:, 2], off[:, 0], atol=1e-9)
    np.testing.assert_allclose(rot[:, 1], off[:, 1], atol=1e-9)


def test_dispatch_by_kind(mocap_dir, mocap_manifest):
    kinds = {name: mocap_kind(mocap_dir / name, entry) for name, entry in mocap_manifest.items()}
    assert {n for n, k in kinds.items() if k == "deepmimic"} == {
        n for n in kinds if n.startswith(("deepmimic-cmu/", "deepmimic/txt/"))}
    assert {n for n, k in kinds.items() if k == "expmap"} == {n for n in kinds if n.startswith("cmu-bench/")}
    # Without the manifest's rig the file itself tells.
    for name in ("deepmimic-cmu/02_01.txt", "cmu-bench/test/running/running_1.txt", "acrnn/indian_04.bvh"):
        assert mocap_kind(mocap_dir / name) == kinds[name]


def test_load_mocap_without_manifest_uses_the_files_rate(mocap_dir):
    a = load_mocap(mocap_dir / "deepmimic-cmu" / "88_06.txt", manifest=None)
    assert a.fps == 30.0 and a.label is None  # the file says 1/30 s; only the manifest knows it is 15
    b = load_mocap(mocap_dir / "acrnn" / "salsa_01a.bvh", manifest=None)
    assert b.fps == 120.0 and b.num_frames == 2243  # header rate, no trim
    c = load_mocap(mocap_dir / "cmu-bench" / "test" / "running" / "running_1.txt", target_fps=25)
    assert c.fps == 25.0 and c.num_frames == int((163 - 1 - 1) * 25 / 120) + 1


def _bad_mocap_files(tmp: Path, mocap_dir: Path) -> dict[str, tuple[Path, str]]:
    """name -> (file, a phrase its one-line error names)."""
    dm = tmp / "dm"
    dm.mkdir()
    shutil.copy(mocap_dir / "deepmimic" / "humanoid3d_character.txt", dm)
    good = (mocap_dir / "deepmimic-cmu" / "02_01.txt").read_text()
    (dm / "truncated.txt").write_text(good[: len(good) // 2])
    frames = json.loads(good)
    frames["Frames"][3] = frames["Frames"][3][:-1]
    (dm / "short_frame.txt").write_text(json.dumps(frames))
    frames = json.loads(good)
    frames["Frames"][0][0] = 0.0
    (dm / "zero_duration.txt").write_text(json.dumps(frames))
    (dm / "no_frames.txt").write_text('{"Loop": "none", "Frames": []}')
    lonely = tmp / "lonely"
    lonely.mkdir()
    frames = json.loads(good)
    frames["Frames"] = [row[:-4] for row in frames["Frames"]]  # another character's frames (one joint fewer)
    (lonely / "alone.txt").write_text(json.dumps(frames))
    em = tmp / "em"
    em.mkdir()
    shutil.copy(mocap_dir / "cmu-bench" / "skeleton.json", em)
    lines = (mocap_dir / "cmu-bench" / "test" / "running" / "running_1.txt").read_text().splitlines()
    (em / "ragged.txt").write_text("\n".join(lines[:5] + [",".join(lines[5].split(",")[:-2])] + lines[6:]))
    (em / "word.txt").write_text("\n".join(lines[:3] + [lines[3].replace(lines[3].split(",")[7], "abc", 1)]))
    (em / "rest_only.txt").write_text(lines[0] + "\n")
    (em / "binary.txt").write_bytes(np.random.default_rng(0).integers(0, 256, 2048, dtype=np.uint8).tobytes())
    return {
        "truncated DeepMimic JSON": (dm / "truncated.txt", "not valid JSON"),
        "DeepMimic frame of the wrong length": (dm / "short_frame.txt", "frame 3: expected 44 numbers"),
        "zero frame duration": (dm / "zero_duration.txt", "duration must be positive"),
        "no frames": (dm / "no_frames.txt", "empty"),
        "lone file of another character": (lonely / "alone.txt", "pass --character FILE"),
        "ragged exp-map line": (em / "ragged.txt", "line 6: expected 117"),
        "word in an exp-map line": (em / "word.txt", "line 4: a value is not a number"),
        "only the rest-pose line": (em / "rest_only.txt", "no motion lines"),
        "binary .txt": (em / "binary.txt", "not a text file"),
    }


BAD_CASES = ["truncated DeepMimic JSON", "DeepMimic frame of the wrong length", "zero frame duration", "no frames",
             "lone file of another character", "ragged exp-map line", "word in an exp-map line", "only the rest-pose line",
             "binary .txt"]


@pytest.mark.parametrize("case", BAD_CASES)
def test_bad_mocap_file_one_line_exit_2(case, tmp_path, mocap_dir, capsys):
    from motion2video.cli import main

    path, phrase = _bad_mocap_files(tmp_path, mocap_dir)[case]
    with pytest.raises(InputError) as info:
        load_motion(path)
    assert phrase in str(info.value) and str(path) in str(info.value) and "\n" not in str(info.value)
    out = tmp_path / "out.mp4"
    code = main(["render", str(path), "-o", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    lines = [line for line in err.strip().splitlines() if not line.startswith("note:")]  # the default character's
    assert len(lines) == 1 and phrase in lines[0] and "Traceback" not in err
    assert not out.exists()
