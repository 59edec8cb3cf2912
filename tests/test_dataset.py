"""The motion data pipeline: pure window functions, the split, statistics, augmentation, 2D and face data."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from motion2video.data import corpus
from motion2video.data import windows as W
from motion2video.data.dataset import (
    Clip,
    DatasetConfig,
    Split,
    build_dataset,
    clip_group,
    coarse_label,
    decode_samples,
    encode_observation,
    encode_windows,
    make_split,
)
from motion2video.data.face_data import face_mirror_permutation, mirror_face
from motion2video.core.errors import InputError
from motion2video.core.motion import ARKIT_NAMES
from motion2video.core.skeletons import H36M_17


@pytest.fixture(scope="module")
def mocap(mocap_dir):
    """The real mocap folder (275 clips of every format, manifest) as a body3d dataset."""
    return build_dataset(mocap_dir, DatasetConfig())


def _random_joints(rng, b=2, t=5):
    return rng.normal(size=(b, t, 17, 3)) + np.array([0.0, 0.0, 1.0])


# --- pure functions ---------------------------------------------------------------------------------------


def test_features_round_trip_and_layout():
    rng = np.random.default_rng(0)
    joints = _random_joints(rng)
    f = W.joints_to_features(joints)
    assert f.shape == (2, 5, 51)
    np.testing.assert_allclose(f[..., 48:], joints[..., 0, :])  # the root comes last
    np.testing.assert_allclose(f[..., :3], joints[..., 1, :] - joints[..., 0, :])  # then root-relative joints
    np.testing.assert_allclose(W.features_to_joints(f, dim=3), joints, atol=1e-12)
    assert W.FeatureLayout("body2d").num_features == 34 and W.FeatureLayout("face").num_features == 58


def test_canonical_frame_faces_minus_y_and_round_trips():
    rng = np.random.default_rng(1)
    joints = _random_joints(rng, b=3, t=4)
    frame = W.canonical_frame(joints, anchor=2)
    canon = W.to_canonical(joints, frame)
    hips = canon[:, 2, 4] - canon[:, 2, 1]  # left hip - right hip at the anchor
    np.testing.assert_allclose(hips[:, 1], 0.0, atol=1e-12)
    assert np.all(hips[:, 0] > 0)  # hips along +x: the body faces -y
    np.testing.assert_allclose(canon[:, 2, 0, :2], 0.0, atol=1e-12)  # anchor root at the origin
    np.testing.assert_allclose(canon[..., 2], joints[..., 2], atol=1e-12)  # heights untouched
    np.testing.assert_allclose(W.from_canonical(canon, frame), joints, atol=1e-12)
    with_samples = np.repeat(canon[:, None], 2, axis=1)  # (B, K, T, J, 3)
    np.testing.assert_allclose(W.from_canonical(with_samples, frame)[:, 1], joints, atol=1e-12)


def test_resample_and_speed_window():
    x = np.arange(11, dtype=np.float64)[:, None]  # 10 fps ramp
    np.testing.assert_allclose(W.resample(x, 10.0, 5.0)[:, 0], [0, 2, 4, 6, 8, 10])
    np.testing.assert_allclose(W.speed_window(x, start=1.0, length=4, speed=1.0)[:, 0], [1, 2, 3, 4])
    np.testing.assert_allclose(W.speed_window(x, start=0.5, length=3, speed=1.5)[:, 0], [0.5, 2.0, 3.5])
    np.testing.assert_array_equal(W.sliding_starts(10, length=4, stride=3), [0, 3, 6])
    assert len(W.sliding_starts(3, length=4, stride=1)) == 0


def test_mirror_and_rotation():
    rng = np.random.default_rng(2)
    joints = _random_joints(rng)[0]
    perm = H36M_17.mirror_permutation()
    m = W.mirror_joints(joints, perm)
    np.testing.assert_allclose(m[:, 1, 0], -joints[:, 4, 0])  # right hip <- mirrored left hip
    np.testing.assert_allclose(W.mirror_joints(m, perm), joints)
    r = W.rotate_about_z(joints, np.pi / 2, centre=np.zeros(3))
    np.testing.assert_allclose(r[..., 0], -joints[..., 1], atol=1e-6)
    np.testing.assert_allclose(r[..., 1], joints[..., 0], atol=1e-6)


def test_face_mirror_swaps_left_and_right():
    perm = face_mirror_permutation()
    i, j = ARKIT_NAMES.index("eyeBlinkLeft"), ARKIT_NAMES.index("eyeBlinkRight")
    assert perm[i] == j and perm[j] == i
    assert perm[ARKIT_NAMES.index("jawOpen")] == ARKIT_NAMES.index("jawOpen")
    p = np.random.default_rng(3).uniform(size=(4, 58))
    m = mirror_face(p)
    assert m[0, i] == p[0, j] and m[0, 53] == -p[0, 53] and m[0, 55] == -p[0, 55] and m[0, 52] == p[0, 52]
    np.testing.assert_allclose(mirror_face(m), p)


def test_labels_and_groups():
    assert coarse_label("walk (start-walk-stop, MJ style)") == "walk"
    assert coarse_label("dance_a") == "dance" and coarse_label(None) is None
    assert clip_group("cmu/08_11.bvh") == "cmu-08" and clip_group("cmu/131_02.bvh") == "cmu-131"
    assert clip_group("mass/mass_walk.bvh") == "mass" and clip_group("other/clip.bvh") == "other/clip.bvh"
    # Across folders: the CMU subject from the stem, or from the trial a cmu-bench label names.
    assert clip_group("deepmimic-cmu/88_06.txt") == "cmu-88"
    assert clip_group("cmu-bench/train/jumping/jumping_1.txt", "jump (cmu-bench train jumping_1; CMU 13_11)") == "cmu-13"
    assert clip_group("cmu-bench/train/jumping/jumping_2.txt", "jump (cmu-bench train jumping_2)") == "cmu-bench:jumping"
    # acrnn by action: salsa is subjects 60/61 (both dancers of a take together), indian 94, martial 135.
    assert clip_group("acrnn/salsa_03a.bvh") == clip_group("acrnn/salsa_03b.bvh") == "cmu-60-61"
    assert clip_group("acrnn/indian_04.bvh") == "cmu-94" and clip_group("acrnn/martial_03.bvh") == "cmu-135"
    # A DeepMimic BVH and its .txt original are one source.
    assert clip_group("deepmimic/humanoid3d_run.bvh") == clip_group("deepmimic/txt/humanoid3d_run.txt")
    assert coarse_label("salsa dance (partner a of take 01)") == "salsa"
    assert coarse_label("HandStandKicks") == "handstand" and coarse_label("forward jump") == "jump"


def test_split_holds_out_whole_groups_deterministically():
    clips = [Clip(f"cmu/{s:02d}_{t:02d}.bvh", np.zeros((100, 17, 3), np.float32), None, clip_group(f"{s:02d}_{t:02d}"))
             for s in range(1, 9) for t in range(1, 4)] + [Clip("other/a.bvh", np.zeros((50, 17, 3)), None, "other/a.bvh")]
    a = make_split(clips, val_fraction=0.1, test_fraction=0.15, seed=0, pinned=False)
    b = make_split(list(reversed(clips)), val_fraction=0.1, test_fraction=0.15, seed=0, pinned=False)
    assert set(a.test) == set(b.test) and set(a.val) == set(b.val)
    groups = {name: clip_group(name) for name in a.train + a.val + a.test}
    for s1, s2 in [("train", "test"), ("train", "val"), ("val", "test")]:
        assert not {groups[n] for n in a.names(s1)} & {groups[n] for n in a.names(s2)}
    assert any(n.startswith("cmu/") for n in a.test)
    assert len(a.train) + len(a.val) + len(a.test) == len(clips)
    assert make_split(clips, val_fraction=0.1, test_fraction=0.15, seed=1, pinned=False) != a
    # The corpus rule: pinned groups (cmu-02 test, cmu-03 val) decide; the seed does not matter.
    pinned = make_split(clips, val_fraction=0.1, test_fraction=0.15, seed=0)
    assert pinned == make_split(clips, val_fraction=0.1, test_fraction=0.15, seed=1)
    assert {clip_group(n) for n in pinned.test} == {"cmu-02"} and {clip_group(n) for n in pinned.val} == {"cmu-03"}
    assert len(pinned.train) == len(clips) - 6


def test_duplicates_and_linked_groups():
    rows = [("cmu/02_01.bvh", "walk"), ("deepmimic-cmu/02_01.txt", "walk"),
            ("cmu-bench/train/walking/walking_1.txt", "walk (cmu-bench train walking_1; CMU 02_01)"),
            ("cmu-bench/train/walking/walking_9.txt", "walk (cmu-bench train walking_9)"),
            ("deepmimic-cmu/10_05.txt", "soccer"), ("cmu-bench/train/soccer/soccer_4.txt", "soccer (...; CMU 10_05)"),
            ("deepmimic/humanoid3d_run.bvh", "run"), ("deepmimic/txt/humanoid3d_run.txt", "run")]
    assert corpus.duplicates(rows) == {
        "deepmimic-cmu/02_01.txt": "cmu/02_01.bvh", "cmu-bench/train/walking/walking_1.txt": "cmu/02_01.bvh",
        "deepmimic-cmu/10_05.txt": "cmu-bench/train/soccer/soccer_4.txt",
        "deepmimic/txt/humanoid3d_run.txt": "deepmimic/humanoid3d_run.bvh"}
    # An unidentified benchmark walk may be subject 2: its group is linked with cmu-02.
    linked = corpus.link_groups([(n, clip_group(n, label)) for n, label in rows])
    assert linked["cmu-02"] == linked["cmu-bench:walking"] == "cmu-02+cmu-bench:walking"
    assert linked["cmu-10"] == "cmu-10" and corpus.pinned_split(linked["cmu-02"]) == "test"


# --- the real dataset ---------------------------------------------------------------------------------------


@pytest.mark.slow
def test_real_split_is_subject_disjoint_across_folders_and_recorded(mocap, mocap_manifest):
    split = mocap.split
    index = corpus.corpus_index(mocap.source)
    assert len(index.dropped) == 50  # 15 cmu-bench, 20 deepmimic-cmu and 15 DeepMimic .txt copies
    assert len(split.train) + len(split.val) + len(split.test) == len(mocap_manifest) - 50 == 225
    assert not set(index.dropped) & set(split.train + split.val + split.test)
    # Every CMU subject (and every source without subjects) sits in one split only, whatever its folder.
    labels = {n: e.label for n, e in mocap_manifest.items()}
    where: dict[str, set] = {}
    for s in ("train", "val", "test"):
        for n in split.names(s):
            where.setdefault(clip_group(n, labels[n]), set()).add(s)
    assert all(len(v) == 1 for v in where.values()), {g: v for g, v in where.items() if len(v) > 1}
    assert where["cmu-60-61"] == {"train"} and where["cmu-94"] == {"test"} and where["cmu-131"] == {"test"}
    assert where["mass"] == {"val"} and where["deepmimic"] == {"train"}
    # The two dancers of a salsa take are together; test holds whole subjects of several actions.
    assert {c.label for c in mocap.clips_of("test")} >= {"walk", "indian dance", "get up", "jump"}
    minutes = {s: sum(c.num_frames for c in mocap.clips_of(s)) / 25 / 60 for s in ("train", "val", "test")}
    assert 29 < minutes["train"] < 31 and 4 < minutes["test"] < 5 and 1.5 < minutes["val"] < 2
    assert Split.from_dict(split.to_dict()) == split
    assert mocap.summary["per_split"]["train"]["clips"] == len(split.train)


@pytest.mark.slow
def test_old_checkpoint_split_on_the_grown_folder(mocap):
    """A 72-clip checkpoint's recorded split (the 5-minute mtvae-add's, kept as a fixture) on the 275-file
    folder: its clips keep their split; new clips are test clips only when no clip of their subject was trained
    or validated on."""
    import json
    from pathlib import Path

    from motion2video.data.dataset import Split, extend_split

    fixture = Path(__file__).parent / "fixtures" / "split_72clips.json"
    old = Split.from_dict(json.loads(fixture.read_text())["split"])
    assert len(old.train) + len(old.val) + len(old.test) == 72
    ext = extend_split(old, mocap.clips)
    assert (ext.train, ext.val) == (old.train, old.val) and ext.test[:len(old.test)] == old.test
    groups = {c.name: c.group for c in mocap.clips}
    seen = {groups[n] for n in old.train + old.val if n in groups}
    new_test = ext.test[len(old.test):]
    assert new_test and not {groups[n] for n in new_test} & seen
    assert any(n.startswith("acrnn/salsa") for n in new_test)  # subjects the old models never saw
    assert not any(groups[n] == "cmu-13+cmu-49+cmu-bench:jumping" for n in new_test)  # 13 was trained on
    # --recorded-only: the checkpoint's own clips, as its results were measured; "all": every new clip.
    assert extend_split(old, mocap.clips, new_clips="none") == old
    assert len(extend_split(old, mocap.clips, new_clips="all").test) == len(old.test) + len(mocap.clips) - 72
    again = build_dataset(mocap.source, mocap.config, split=old, stats=mocap.stats, clips=mocap.clips,
                          recorded_only=True)
    assert again.split == old and again.clips_of("test")[0].name == old.test[0]


@pytest.mark.slow
def test_stats_come_from_the_training_split(mocap):
    train = mocap.windows("train")
    assert train.raw.shape[1:] == (64, 51)
    stats = W.compute_stats(train.raw)
    np.testing.assert_allclose(stats.mean, mocap.stats.mean, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(stats.std, mocap.stats.std, rtol=1e-5, atol=1e-6)
    assert abs(float(train.features.mean())) < 0.05 and abs(float(train.features.std()) - 1.0) < 0.1
    test = mocap.windows("test", stride=16)
    assert set(test.clip_names) <= set(mocap.split.test) and len(test) > 10


@pytest.mark.slow
def test_windows_decode_back_to_the_clip(mocap):
    w = mocap.windows("test", stride=16)
    joints = decode_samples(w.features[:, None], config=mocap.config, stats=mocap.stats, frame=w.frames)[:, 0]
    clips = {c.name: c for c in mocap.clips}
    for i in (0, len(w) - 1):
        original = clips[w.clip_names[i]].data[w.starts[i]:w.starts[i] + 64]
        np.testing.assert_allclose(joints[i], original, atol=2e-4)


@pytest.mark.slow
def test_encode_observation_matches_window_encoding(mocap):
    w = mocap.windows("test", stride=16)
    clip = next(c for c in mocap.clips if c.name == w.clip_names[0])
    obs = clip.data[w.starts[0]:w.starts[0] + 16]
    feats, frame = encode_observation(obs, config=mocap.config, stats=mocap.stats)
    np.testing.assert_allclose(feats[0], w.obs[0], atol=1e-4)
    np.testing.assert_allclose(frame.angle, w.frames.angle[:1])


@pytest.mark.slow
def test_sample_batch_is_seeded_and_augmented(mocap):
    a = mocap.sample_batch(np.random.default_rng(5), 16)
    b = mocap.sample_batch(np.random.default_rng(5), 16)
    c = mocap.sample_batch(np.random.default_rng(6), 16)
    assert a.shape == (16, 64, 51) and a.dtype == np.float32
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 0.1
    plain = mocap.sample_batch(np.random.default_rng(5), 16, augment=False)
    assert np.abs(plain - a).max() > 0.01


@pytest.mark.slow
def test_mirrored_window_encodes_the_mirrored_pose(mocap):
    clip = next(c for c in mocap.clips if c.num_frames >= 64)
    window = clip.data[None, :64]
    mirrored = W.mirror_joints(window, H36M_17.mirror_permutation())
    f, _ = encode_windows(window, config=mocap.config)
    fm, _ = encode_windows(mirrored, config=mocap.config)
    # In the canonical frame a mirrored body is the original with x negated and sides swapped.
    expected = W.joints_to_features(W.mirror_joints(W.features_to_joints(f, dim=3), H36M_17.mirror_permutation()))
    np.testing.assert_allclose(fm, expected, atol=1e-5)


def test_body2d_variant_projects_to_the_virtual_camera(mocap_dir):
    cfg = DatasetConfig(layout="body2d")
    ds = build_dataset(mocap_dir / "cmu" / "131_02.bvh", cfg)
    w = ds.windows("all")
    assert w.features.shape[-1] == 34
    pixels = decode_samples(w.features[:, None], config=cfg, stats=ds.stats, frame=w.frames)[:, 0]
    assert pixels.shape[-2:] == (17, 2)
    anchor = pixels[:, cfg.observed - 1]
    assert np.all(np.abs(anchor[:, 0, 0] - 128) < 2)  # canonical root at the image centre column
    assert np.all(anchor[:, 10, 1] < anchor[:, 3, 1])  # head above the ankle (y down)


def test_face_dataset_from_a_real_capture(face_dir):
    cfg = DatasetConfig(layout="face")
    ds = build_dataset(face_dir / "llv" / "dao.csv", cfg)
    w = ds.windows("all")
    assert w.features.shape[1:] == (64, 58) and len(w) >= 1
    assert ds.clips[0].data[:, 52:].any()  # dao.csv keeps its real head rotation
    with pytest.raises(InputError, match="face"):
        build_dataset(face_dir / "llv" / "dao.csv", DatasetConfig())


def test_live_link_takes_get_a_procedural_head_pose(face_dir):
    ds = build_dataset(face_dir / "livelinkface" / "apfel.csv", DatasetConfig(layout="face"))
    assert np.abs(ds.clips[0].data[:, 52:55]).max() > 0.01
    zero = build_dataset(face_dir / "livelinkface" / "apfel.csv",
                         dataclasses.replace(DatasetConfig(layout="face"), face_head_pose="zero"))
    assert not zero.clips[0].data[:, 52:].any()


def test_bad_inputs_raise_input_errors(tmp_path, mocap_dir):
    with pytest.raises(InputError, match="no such file"):
        build_dataset(tmp_path / "missing", DatasetConfig())
    with pytest.raises(InputError, match="long enough"):
        build_dataset(mocap_dir / "mass" / "mass_run.bvh", DatasetConfig())
    with pytest.raises(ValueError):
        DatasetConfig(layout="voxels")
