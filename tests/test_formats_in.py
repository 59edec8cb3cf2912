"""Formats in: DeepMimic files as users have them, joint arrays of the motion-generation field, and
the refusal of pickles. Real files from ../shared, copied into the layouts users have."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from motion2video.cli import main
from motion2video.core.errors import InputError
from motion2video.formats.bvh import canonical_positions, read_bvh
from motion2video.formats.deepmimic import DEFAULT_CHARACTER, find_character
from motion2video.formats.io import load_motion
from motion2video.formats.joint_arrays import SMPL_22, load_joint_array, load_joint_futures
from motion2video.formats.mocap import load_mocap

SUBJECT = "85_02"  # a deepmimic-cmu trial (CMU subject 85)


def _fails(args: list[str], capsys) -> str:
    """Run the CLI, expect exit 2 with one error line (besides notes); return it."""
    assert main(args) == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith("note:")]
    assert len(err) == 1 and "Traceback" not in err[0], err
    return err[0]


@pytest.fixture
def motion_file(mocap_dir):
    return mocap_dir / "deepmimic-cmu" / f"{SUBJECT}.txt"


@pytest.fixture
def reference(motion_file):
    """The clip read where the shared data keeps it (character found in deepmimic/), no manifest."""
    return load_mocap(motion_file, manifest=False)


def _scaled_character(mocap_dir, path, scale: float) -> None:
    data = json.loads((mocap_dir / "deepmimic" / "humanoid3d_character.txt").read_text())
    for joint in data["Skeleton"]["Joints"]:
        for axis in "XYZ":
            joint[f"Attach{axis}"] *= scale
    path.write_text(json.dumps(data))


# --- DeepMimic ------------------------------------------------------------------------------------------

def test_deepmimic_repository_layout_finds_its_character(mocap_dir, motion_file, reference, tmp_path, capsys):
    """data/motions/X.txt with data/characters/humanoid3d.txt: that character is used (a scaled copy there
    gives scaled joints), with no note."""
    motions, characters = tmp_path / "data" / "motions", tmp_path / "data" / "characters"
    motions.mkdir(parents=True), characters.mkdir(parents=True)
    shutil.copy(motion_file, motions / motion_file.name)
    shutil.copy(mocap_dir / "deepmimic" / "humanoid3d_character.txt", characters / "humanoid3d.txt")
    assert find_character(motions / motion_file.name) == characters / "humanoid3d.txt"
    got = load_motion(motions / motion_file.name)
    np.testing.assert_allclose(got.joints, reference.joints, atol=1e-6)
    assert "note" not in capsys.readouterr().err
    _scaled_character(mocap_dir, characters / "humanoid3d.txt", 1.25)
    bigger = load_motion(motions / motion_file.name)
    height = lambda m: np.ptp(m.joints[..., 2], axis=1).mean()  # noqa: E731
    assert height(bigger) / height(reference) == pytest.approx(1.25, rel=0.02)


def test_lone_deepmimic_file_uses_the_shipped_character_with_a_note(motion_file, reference, tmp_path, capsys):
    lone = tmp_path / "clip.txt"
    shutil.copy(motion_file, lone)
    assert find_character(lone) is None
    got = load_motion(lone)
    np.testing.assert_allclose(got.joints, reference.joints, atol=1e-6)
    err = capsys.readouterr().err
    assert "note:" in err and "standard humanoid3d" in err and "--character" in err
    assert DEFAULT_CHARACTER.is_file() and (DEFAULT_CHARACTER.parent / "LICENSE-humanoid3d.txt").is_file()


def test_character_flag_on_render_and_sample(mocap_dir, motion_file, reference, tmp_path, capsys):
    """--character FILE wins over the default; render and sample both take it."""
    lone = tmp_path / "clip.txt"
    shutil.copy(motion_file, lone)
    char = tmp_path / "tall.txt"
    _scaled_character(mocap_dir, char, 1.1)
    tall = load_motion(lone, character=char)
    assert not np.allclose(tall.joints, reference.joints, atol=1e-3)
    out = tmp_path / "r.mp4"
    assert main(["render", str(lone), "--character", str(char), "-o", str(out), "--size", "64", "--no-progress"]) == 0
    assert out.stat().st_size > 0 and "note" not in capsys.readouterr().err
    npz = tmp_path / "s.npz"
    assert main(["sample", "--model", "zero-velocity", str(lone), "--character", str(char), "--samples", "1",
                 "--size", "64", "-o", str(tmp_path / "s.mp4"), "--npz", str(npz)]) == 0
    observed = np.load(npz)["observed"]
    assert np.ptp(observed[..., 2], axis=1).mean() > 1.05 * np.ptp(reference.joints[:16, :, 2], axis=1).mean()


def test_bad_character_and_mismatched_motion_fail_in_one_line(mocap_dir, motion_file, tmp_path, capsys):
    lone = tmp_path / "clip.txt"
    shutil.copy(motion_file, lone)
    out = tmp_path / "r.mp4"
    err = _fails(["render", str(lone), "--character", str(tmp_path / "nope.txt"), "-o", str(out)], capsys)
    assert "nope.txt" in err and "no such character file" in err
    bad = tmp_path / "bad.txt"
    bad.write_text("{not json")
    assert "bad.txt" in _fails(["render", str(lone), "--character", str(bad), "-o", str(out)], capsys)
    short = tmp_path / "short.txt"
    data = json.loads(motion_file.read_text())
    data["Frames"] = [row[:-4] for row in data["Frames"]]
    short.write_text(json.dumps(data))
    err = _fails(["render", str(short), "-o", str(out)], capsys)
    assert "short.txt" in err and "--character" in err
    assert not out.exists() and list(tmp_path.glob("*.mp4*")) == []


# --- joint arrays --------------------------------------------------------------------------------------

# SMPL-22 joint -> the CMU Daz BVH node nearest to it (midpoints for SMPL's spine1 and the toes' stand-ins).
DAZ_TO_SMPL = {
    "pelvis": "hip", "left_hip": "lThigh", "right_hip": "rThigh", "spine1": ("hip", "abdomen"),
    "left_knee": "lShin", "right_knee": "rShin", "spine2": "abdomen", "left_ankle": "lFoot",
    "right_ankle": "rFoot", "spine3": "chest", "left_foot": ("lFoot", "lShin"), "right_foot": ("rFoot", "rShin"),
    "neck": "neck", "left_collar": "lCollar", "right_collar": "rCollar", "head": "head",
    "left_shoulder": "lShldr", "right_shoulder": "rShldr", "left_elbow": "lForeArm", "right_elbow": "rForeArm",
    "left_wrist": "lHand", "right_wrist": "rHand",
}


def smpl_array_from_bvh(path) -> tuple[np.ndarray, np.ndarray]:
    """A (T, 22, 3) SMPL-ordered joint array (y up, metres) built from a real CMU BVH's nodes, and the
    clip's canonical joints as the BVH reader gives them (z up, floor not placed)."""
    canon = canonical_positions(read_bvh(path))
    nodes = canon.nodes  # (T, N, 3) metres, z up
    picked = []
    for name in SMPL_22:
        source = DAZ_TO_SMPL[name]
        idx = [canon.index(s) for s in (source if isinstance(source, tuple) else (source,))]
        picked.append(nodes[:, idx].mean(axis=1))
    z_up = np.stack(picked, axis=1)  # (T, 22, 3)
    y_up = np.stack([z_up[..., 0], z_up[..., 2], -z_up[..., 1]], axis=-1)  # z up -> y up: (x, y, z) -> (x, z, -y)
    return y_up, canon.joints


@pytest.mark.parametrize("clip", ["cmu/13_10.bvh", "cmu/02_01.bvh"])
def test_smpl_joint_array_round_trips_a_real_clip(mocap_dir, tmp_path, clip):
    """A 22-joint array made from a CMU BVH reads back onto the BVH reader's canonical joints (within 2 cm,
    all 17: left is left and the body faces the same way), at 20 fps by default."""
    smpl, _ = smpl_array_from_bvh(mocap_dir / clip)
    want = load_mocap(mocap_dir / clip, manifest=False)
    np.save(tmp_path / "j.npy", smpl.astype(np.float32))
    got = load_motion(tmp_path / "j.npy")
    assert got.skeleton == "h36m-17" and got.fps == 20.0 and got.num_frames == want.num_frames
    err = np.linalg.norm(got.joints - want.joints, axis=-1)
    assert err.max() < 0.02, err.max()
    # left/right swapped in the file: the round trip breaks (the test can fail)
    swap = [SMPL_22.index(n.replace("left", "@").replace("right", "left").replace("@", "right")) for n in SMPL_22]
    np.save(tmp_path / "swapped.npy", smpl[:, swap])
    assert np.linalg.norm(load_motion(tmp_path / "swapped.npy").joints - want.joints, axis=-1).max() > 0.1
    # one-array .npz and --input-fps
    np.savez(tmp_path / "j.npz", joints=smpl)
    assert load_motion(tmp_path / "j.npz", fps=30).fps == 30.0


def test_future_grid_renders_k_cells(mocap_dir, tmp_path):
    smpl, _ = smpl_array_from_bvh(mocap_dir / "cmu" / "13_10.bvh")
    futures = np.stack([smpl[k * 40:k * 40 + 25] for k in range(3)])  # (3, 25, 22, 3)
    np.save(tmp_path / "fut.npy", futures)
    motions = load_joint_futures(tmp_path / "fut.npy")
    assert len(motions) == 3 and all(m.num_frames == 25 and m.fps == 20.0 for m in motions)
    out = tmp_path / "fut.mp4"
    assert main(["render", str(tmp_path / "fut.npy"), "-o", str(out), "--size", "64", "--no-progress"]) == 0
    from motion2video.formats.video import read_video

    frames, fps = read_video(out)
    assert frames.shape[:3] == (25, 2 * 64 + 2, 2 * 64 + 2) and fps == pytest.approx(20.0)
    assert frames[:, 64 + 2:, 64 + 2:].max() < 10  # the 4th cell of the 2x2 grid is empty
    assert frames[:, :64, :64].max() > 100


def test_pickles_and_unknown_arrays_are_refused(tmp_path, capsys):
    out = tmp_path / "o.mp4"
    results = tmp_path / "results.npy"  # as MDM writes it: a pickled dict
    np.save(results, np.array({"motion": np.zeros((1, 22, 3, 10)), "text": ["a"]}, dtype=object), allow_pickle=True)
    err = _fails(["render", str(results), "-o", str(out)], capsys)
    assert "results.npy" in err and "pickle" in err and "np.save(" in err
    np.save(tmp_path / "j20.npy", np.zeros((10, 20, 3)))
    assert "(10, 20, 3)" in _fails(["render", str(tmp_path / "j20.npy"), "-o", str(out)], capsys)
    np.savez(tmp_path / "two.npz", a=np.zeros((10, 22, 3)), b=np.zeros(3))
    assert "exactly one joint array" in _fails(["render", str(tmp_path / "two.npz"), "-o", str(out)], capsys)
    nan = np.zeros((10, 22, 3))
    nan[3, 4, 1] = np.nan
    np.save(tmp_path / "nan.npy", nan)
    assert "NaN" in _fails(["render", str(tmp_path / "nan.npy"), "-o", str(out)], capsys)
    np.save(tmp_path / "k.npy", np.zeros((2, 10, 22, 3)))
    with pytest.raises(InputError, match="2 futures"):
        load_joint_array(tmp_path / "k.npy")
    assert not out.exists()


def test_character_reaches_the_commands_that_read_folders(tmp_path, mocap_dir, capsys):
    """--character on train / evaluate / corpus-stats: a folder of DeepMimic motion files of a character that is
    not beside them loads with the flag; a missing character file is one line, exit 2."""
    import shutil

    from motion2video.cli import main
    from motion2video.data.dataset import DatasetConfig, load_clips

    folder = tmp_path / "motions"
    folder.mkdir()
    rows = [line for line in (mocap_dir / "manifest.csv").read_text().splitlines(keepends=True)
            if line.startswith(("file,", "deepmimic-cmu/02_01.txt,", "deepmimic-cmu/02_02.txt,"))]
    (folder / "manifest.csv").write_text("".join(r.replace("deepmimic-cmu/", "") for r in rows))
    for name in ("02_01.txt", "02_02.txt"):
        shutil.copy(mocap_dir / "deepmimic-cmu" / name, folder / name)
    character = mocap_dir / "deepmimic" / "humanoid3d_character.txt"
    clips = load_clips(folder, config=DatasetConfig(), character=character)
    assert len(clips) == 2 and all(c.data.shape[1:] == (17, 3) for c in clips)
    assert main(["corpus-stats", "--data", str(folder), "--character", str(tmp_path / "none.txt")]) == 2
    err = capsys.readouterr().err
    assert "no such character file" in err and len(err.strip().splitlines()) == 1
