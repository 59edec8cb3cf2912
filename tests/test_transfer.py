"""Behaviour transfer (`motion2video transfer`) with tiny behaviour models trained here on real clips, and
its bad-input errors (one line, exit code 2, no output file)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import torch

from motion2video.models.checkpoint import load_model, save_checkpoint
from motion2video.cli import main
from motion2video.data.dataset import DatasetConfig, build_dataset
from motion2video.data.windows import resample, rotate_about_z
from motion2video.formats.io import load_motion, save_motion
from motion2video.evaluation.metrics import MeanStd
from motion2video.core.motion import Motion
from motion2video.models.training import TrainConfig, train_model
from motion2video.evaluation.transfer_protocol import TABLE1_TIMESTEPS, evaluate_transfer, regression_error, transfer_pairs
from motion2video.stages.clips import LoadedClip, load_clip
from motion2video.apps.transfer import transfer_behavior
from motion2video.formats.video import read_image, read_video, write_image
from tests.conftest import link_clips

CLIPS = ("cmu/131_01.bvh", "cmu/131_03.bvh", "cmu/01_01.bvh", "mass/mass_walk.bvh")
TINY = {"hidden_dim": 16, "latent_dim": 4}
HORIZON = 10


def _train(name: str, data, out, *, model: dict | None = None, steps: int = 3, **data_kw):
    """A tiny model trained a few steps (every clip in training: no validation or test split)."""
    config = DatasetConfig(val_fraction=0.0, test_fraction=0.0, **data_kw)
    dataset = build_dataset(data, config)
    train_model(model_name=name, model_config={**TINY, **(model or {})}, dataset=dataset,
                config=TrainConfig(steps=steps, batch_size=4, warmup_steps=0, checkpoint_every=1000, val_every=0,
                                   flow_steps=5, flow_windows=16),
                out=out, progress=False)
    return out


@pytest.fixture(scope="module")
def small_data(tmp_path_factory, mocap_dir):
    return link_clips(tmp_path_factory.mktemp("mocap_transfer"), mocap_dir, CLIPS)


@pytest.fixture(scope="module")
def ckpts(small_data, face_dir, tmp_path_factory):
    d = tmp_path_factory.mktemp("transfer_ckpt")
    return {
        "behavior": _train("behavior", small_data, d / "behavior.safetensors"),
        "mtvae": _train("mtvae-add", small_data, d / "mtvae.safetensors"),
        "face": _train("behavior", face_dir / "llv" / "dao.csv", d / "face.safetensors", layout="face",
                       observed=4, future=12),
    }


@pytest.fixture(scope="module")
def clips(mocap_dir):
    """Source and target come from different BVH rigs (cmu-3dsmax and cmu-mb), both read as canonical
    H36M-17, and at 120 fps, resampled to the model's 25 fps."""
    return {"source": str(mocap_dir / "cmu/131_03.bvh"), "target": str(mocap_dir / "cmu/01_01.bvh")}


def _resampled(path, fps=25.0) -> np.ndarray:
    m = load_motion(path)
    return resample(m.joints, m.fps, fps), m.fps


def test_transfer_skeleton_video_and_npz(ckpts, clips, tmp_path, capsys):
    out, npz = tmp_path / "t.mp4", tmp_path / "t.npz"
    code = main(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                 clips["target"], "--target-frame", "240", "--behavior-start", "60", "--horizon", str(HORIZON),
                 "--style", "skeleton", "--size", "64", "-o", str(out), "--npz", str(npz)])
    assert code == 0 and "wrote" in capsys.readouterr().out
    frames, fps = read_video(out)
    assert fps == 25.0 and frames.shape == (1 + HORIZON, 64, 2 * 64 + 2, 3)
    saved = np.load(npz)
    target, target_fps = _resampled(clips["target"])
    source, source_fps = _resampled(clips["source"])
    start = int(np.floor(240 * 25 / target_fps + 0.5))
    s = int(np.floor(60 * 25 / source_fps + 0.5))
    # the re-enactment starts exactly at the target's posture; the source panel is the source itself
    np.testing.assert_allclose(saved["reenacted"][0, 0], target[start], atol=1e-5)
    np.testing.assert_allclose(saved["source"], source[s:s + 1 + HORIZON], atol=1e-5)
    assert saved["reenacted"].shape == (1, 1 + HORIZON, 17, 3) and saved["z"].shape == (1, 4)
    assert np.all(np.isfinite(saved["reenacted"]))


def test_reenactment_follows_the_target_position_and_heading(ckpts, clips):
    """The root moves relative to the target's start position and heading: turning and moving the target
    turns and moves the whole re-enactment the same way."""
    bundle = load_model(ckpts["behavior"])
    source = load_clip(bundle, clips["source"])
    target = load_clip(bundle, clips["target"])
    moved = LoadedClip(data=rotate_about_z(target.data, 1.1, np.array([2.0, -1.0, 0.0])) + np.float32([0.5, 3, 0]),
                       fps=target.fps, source_fps=target.source_fps, source_frames=target.source_frames,
                       path="moved")
    a = transfer_behavior(bundle, source, target, target_frame=100, horizon=HORIZON).reenacted[0]
    b = transfer_behavior(bundle, source, moved, target_frame=100, horizon=HORIZON).reenacted[0]
    expected = rotate_about_z(a, 1.1, np.array([2.0, -1.0, 0.0])) + np.float32([0.5, 3, 0])
    np.testing.assert_allclose(b, expected, atol=1e-4)


def test_reenactment_keeps_the_target_start_and_its_bone_lengths(ckpts, clips):
    """The re-enactment starts at the target's posture and every generated frame has the start
    posture's bone lengths (a tiny, barely trained model's raw joints stretch its bones)."""
    from motion2video.evaluation.signatures import bone_length_spread, bone_lengths

    bundle = load_model(ckpts["behavior"])
    source = load_clip(bundle, clips["source"])
    target = load_clip(bundle, clips["target"])
    result = transfer_behavior(bundle, source, target, target_frame=100, horizon=HORIZON)
    seq = result.reenacted[0]
    start = _resampled(clips["target"])[0][int(np.floor(100 * 25.0 / 120.0 + 0.5))]
    np.testing.assert_allclose(seq[0], start, atol=1e-4)
    assert bone_length_spread(seq) < 1e-5
    np.testing.assert_allclose(bone_lengths(seq[1:]), np.repeat(bone_lengths(seq[:1]), HORIZON, axis=0), atol=1e-5)
    assert np.abs(np.diff(seq[:, 0], axis=0)).max() > 0  # the body moves


def test_adapting_the_decoder_fits_the_source_and_leaves_the_model_as_it_was(ckpts, clips):
    """adapt_to_source: a copy whose decoder re-enacts the source from its own start posture closer than the
    trained one did, by moving only the decoder; the trained model's weights do not change; the same inputs give
    the same adapted weights; 0 steps is the model itself; through transfer_behavior, the adapted re-enactment
    starts at the same target posture as the one as trained (adapt_steps=0) and then differs from it."""
    from motion2video.stages.latents import (adapt_to_source, behavior_latents, behavior_root, encode_sequences,
                                             reenact)

    bundle = load_model(ckpts["behavior"])
    model = bundle.model
    source = load_clip(bundle, clips["source"])
    feats, _ = encode_sequences(bundle, source.data[None, 40:40 + 1 + HORIZON])  # (1, 1 + H, F)
    z = behavior_latents(model, feats)
    before = {k: v.clone() for k, v in model.state_dict().items()}

    def error(m):
        made = reenact(m, z, feats[:, 0], horizon=HORIZON, root=behavior_root(m, feats, feats[:, 0]))
        return float(np.square(made - feats[:, 1:]).sum())

    adapted = adapt_to_source(model, feats, z, steps=60)
    again = adapt_to_source(model, feats, z, steps=60)
    assert adapted is not model and error(adapted) < 0.5 * error(model)
    for key, value in model.state_dict().items():
        assert torch.equal(value, before[key]), key
    for (key, a), b in zip(adapted.state_dict().items(), again.state_dict().values()):
        assert torch.equal(a, b), key
    changed = [k for k, v in adapted.state_dict().items() if not torch.equal(v, before[k])]
    assert changed and all(k.startswith("decoder.") for k in changed)  # only the decoder moves
    assert not any(p.requires_grad for p in adapted.parameters())
    assert adapt_to_source(model, feats, z, steps=0) is model
    target = load_clip(bundle, clips["target"])
    as_trained = transfer_behavior(bundle, source, target, target_frame=100, horizon=HORIZON, adapt_steps=0)
    fitted = transfer_behavior(bundle, source, target, target_frame=100, horizon=HORIZON, adapt_steps=60)
    np.testing.assert_array_equal(as_trained.reenacted[0, 0], fitted.reenacted[0, 0])  # both start at the target
    assert np.abs(as_trained.reenacted[0, 1:] - fitted.reenacted[0, 1:]).max() > 1e-3


def test_decoders_fitted_side_by_side_move_as_each_fitted_alone(ckpts, clips):
    """adapt_to_sources fits one decoder copy per source in one vmapped loop: each ends where fitting it alone
    (adapt_to_source) ends, to float rounding, and differs from the other source's."""
    from motion2video.stages.latents import adapt_to_source, adapt_to_sources, behavior_latents, encode_sequences

    bundle = load_model(ckpts["behavior"])
    model = bundle.model
    data = load_clip(bundle, clips["source"]).data
    feats, _ = encode_sequences(bundle, np.stack([data[40:40 + 1 + HORIZON], data[10:10 + 1 + HORIZON]]))
    z = behavior_latents(model, feats)
    together = adapt_to_sources(model, feats, z, steps=20)
    alone = [adapt_to_source(model, feats[i:i + 1], z[i:i + 1], steps=20) for i in range(2)]
    for a, b in zip(together, alone):
        for (key, x), y in zip(a.decoder.state_dict().items(), b.decoder.state_dict().values()):
            torch.testing.assert_close(x, y, atol=1e-5, rtol=1e-4, msg=key)
    first, second = (m.decoder.state_dict()["out.weight"] for m in together)
    assert not torch.allclose(first, second)
    assert adapt_to_sources(model, feats, z, steps=0) == [model, model]


def test_flow_samples_grid_is_seeded(ckpts, clips, tmp_path):
    paths = {}
    for name, seed in (("a", 3), ("b", 3), ("c", 4)):
        out, npz = tmp_path / f"{name}.mp4", tmp_path / f"{name}.npz"
        code = main(["transfer", "--model", str(ckpts["behavior"]), "--sample", "3", "--target", clips["target"],
                     "--horizon", str(HORIZON), "--style", "skeleton", "--size", "48", "--seed", str(seed),
                     "-o", str(out), "--npz", str(npz)])
        assert code == 0
        paths[name] = np.load(npz)
    frames, _ = read_video(tmp_path / "a.mp4")
    assert frames.shape[0] == 1 + HORIZON and frames.shape[1:3] == (2 * 48 + 2, 2 * 48 + 2)  # 2x2 grid, 3 cells
    assert paths["a"]["reenacted"].shape == (3, 1 + HORIZON, 17, 3) and "source" not in paths["a"]
    np.testing.assert_array_equal(paths["a"]["reenacted"], paths["b"]["reenacted"])
    assert not np.allclose(paths["a"]["reenacted"], paths["c"]["reenacted"])


def test_resampled_target_gives_the_same_start_posture(ckpts, clips, tmp_path):
    """A target at another frame rate is resampled; --target-frame counts the file's own frames."""
    target, _ = _resampled(clips["target"])
    path50 = save_motion(Motion(resample(target, 25.0, 50.0), 50.0), tmp_path / "target50.npz")
    out = {}
    for name, path, frame in (("25", None, 40), ("50", path50, 80)):
        if path is None:
            path = save_motion(Motion(target, 25.0), tmp_path / "target25.npz")
        npz = tmp_path / f"{name}.npz"
        assert main(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                     str(path), "--target-frame", str(frame), "--horizon", "4", "--style", "skeleton", "--size",
                     "32", "-o", str(tmp_path / f"{name}.mp4"), "--npz", str(npz)]) == 0
        out[name] = np.load(npz)["reenacted"]
    np.testing.assert_allclose(out["50"], out["25"], atol=1e-4)


@pytest.mark.slow
def test_transfer_mesh_shows_another_person(ckpts, clips, tmp_path):
    out = tmp_path / "mesh.mp4"
    code = main(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                 clips["target"], "--horizon", "3", "--size", "64", "-o", str(out)])
    assert code == 0
    frames, _ = read_video(out)
    assert frames.shape == (4, 64, 130, 3)
    left, right = frames[:, 6:-6, 6:58].astype(int), frames[:, 6:-6, 72:-6].astype(int)
    reddish = lambda x: ((x[..., 0] > 150) & (x[..., 1] < 110) & (x[..., 2] < 110)).sum()  # noqa: E731
    assert reddish(right) > 20 and reddish(left) < reddish(right) / 4  # the target's red top, not the source's


@pytest.fixture(scope="module")
def frame_ckpt(tmp_path_factory):
    """An untrained (residual: it starts as copy-reference) tiny body frame generator."""
    from motion2video.generator.checkpoint import save_frame_model
    from motion2video.generator.model import FrameGenerator, FrameGeneratorConfig

    torch.manual_seed(0)
    gen = FrameGenerator(FrameGeneratorConfig(image_size=32, channels=(4, 8)))
    return save_frame_model(gen, tmp_path_factory.mktemp("frames") / "frames.safetensors", step=0)


@pytest.mark.slow
def test_transfer_frames_style_with_reference(ckpts, clips, frame_ckpt, tmp_path, capsys):
    person = read_image(Path(__file__).resolve().parents[1] / "demo_inputs" / "reference_body_128.png").copy()
    person[person.astype(int).min(axis=2) > 235] = (0, 0, 200)  # the white backdrop made blue
    ref = np.zeros((128, 192, 3), np.uint8)
    ref[:, :, 2] = 200
    ref[:, 32:160] = person  # a wide picture of a person on blue, no pose file beside it: the pose is estimated
    write_image(tmp_path / "ref.png", ref)
    out = tmp_path / "frames.mp4"
    code = main(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                 clips["target"], "--horizon", "3", "--size", "32", "--frame-model", str(frame_ckpt),
                 "--reference", str(tmp_path / "ref.png"), "-o", str(out)])
    assert code == 0
    assert "note: reference image is 192x128" in capsys.readouterr().err  # padded and resized, with a note
    frames, _ = read_video(out)
    assert frames.shape == (4, 32, 66, 3)
    assert frames[:, 5:11, 40:62, 2].mean() > 150  # above the label: the generator copies the blue reference
    assert frames[:, 20:28, 40:62, 2].mean() < 100  # the label (a dark box) sits at the bottom of a frames cell


@pytest.mark.slow
def test_transfer_frames_style_renders_its_own_reference(ckpts, clips, frame_ckpt, tmp_path):
    out = tmp_path / "frames.mp4"
    code = main(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                 clips["target"], "--horizon", "2", "--size", "32", "--style", "frames", "--frame-model",
                 str(frame_ckpt), "-o", str(out)])
    assert code == 0
    frames, _ = read_video(out)
    right = frames[:, 4:12, 38:62].astype(int)  # above the label: the rendered Anny reference, white background
    assert frames.shape == (3, 32, 66, 3) and right.mean() > 100


@pytest.mark.slow
def test_face_transfer_renders_another_face(ckpts, face_dir, tmp_path):
    out, npz = tmp_path / "face.mp4", tmp_path / "face.npz"
    source, target = face_dir / "livelinkface" / "S07-001.csv", face_dir / "llv" / "dao.csv"
    code = main(["transfer", "--model", str(ckpts["face"]), "--behavior", str(source), "--target", str(target),
                 "--target-frame", "30", "--horizon", "3", "--size", "48", "-o", str(out), "--npz", str(npz)])
    assert code == 0
    frames, _ = read_video(out)
    assert frames.shape == (4, 48, 98, 3)
    saved = np.load(npz)
    dao = load_motion(target)
    np.testing.assert_allclose(saved["reenacted"][0, 0], resample(dao.params, dao.fps, 25.0)[13], atol=1e-5)
    assert np.all((saved["reenacted"][..., :52] >= 0) & (saved["reenacted"][..., :52] <= 1))
    # neither file names an identity: the target is drawn as another face (other skin), not the source's
    assert np.abs(frames[:, 14:, 8:40].astype(int) - frames[:, 14:, 58:90].astype(int)).mean() > 3


def test_the_table1_protocol_runs_on_tiny_models(ckpts, small_data):
    bundle = load_model(ckpts["behavior"])
    dataset = build_dataset(small_data, bundle.data_config, split=bundle.meta.split, stats=bundle.stats)
    windows = dataset.windows("train", stride=32)
    pairs = transfer_pairs(windows.clip_names, seed=0)
    names = np.asarray(windows.clip_names)
    assert np.all(names[pairs] != names)
    for ckpt in (ckpts["behavior"], ckpts["mtvae"]):
        scores = evaluate_transfer(load_model(ckpt), windows, windows, pairs=pairs)
        assert set(scores.tde) == set(scores.re) == set(TABLE1_TIMESTEPS)
        assert all(np.isfinite(v) and v >= 0 for v in [*scores.tde.values(), *scores.re.values()])
        assert isinstance(scores.d_beta, MeanStd) and scores.d_beta.mean >= 0
        assert {"self", "transfer", "prior"} <= set(scores.realism)
        assert all(0.0 <= v <= 1.0 for v in scores.realism.values())
    assert "flow" in evaluate_transfer(bundle, windows, windows, pairs=pairs).realism


def test_sample_realism_measures_every_sample_and_one_per_window(ckpts, small_data):
    """Liveliness over all K samples per window, the ground truth's from the windows themselves (the same
    for every model), classifier accuracies in [0, 1]."""
    from motion2video.evaluation.transfer_protocol import motion_liveliness, sample_realism

    for ckpt in (ckpts["behavior"], ckpts["mtvae"]):
        bundle = load_model(ckpt)
        dataset = build_dataset(small_data, bundle.data_config, split=bundle.meta.split, stats=bundle.stats)
        windows = dataset.windows("train", stride=32)
        r = sample_realism(bundle, windows, samples=3, seed=0)
        assert (r.windows, r.samples_per_window) == (len(windows.features), 3)
        assert r.real == pytest.approx(motion_liveliness(bundle.stats.denormalize(windows.future)))
        assert all(v > 0 for v in r.samples) and 0.0 <= r.realism <= 1.0 and 0.0 <= r.realism_poses <= 1.0
        assert sample_realism(bundle, windows, samples=3, seed=0) == r  # seeded


def test_regression_error_is_zero_for_linear_postures():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(200, 5))
    w = rng.normal(size=(5, 7))
    assert regression_error(z[:150], z[:150] @ w, z[150:], z[150:] @ w, l2=1e-9) < 1e-12
    assert regression_error(z[:150], rng.normal(size=(150, 7)), z[150:], rng.normal(size=(50, 7))) > 0.5


# --- bad input ----------------------------------------------------------------------------------------------


def _fails(argv, capsys, *outputs) -> str:
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and err.startswith("motion2video transfer: error:"), err
    for path in outputs:
        assert not path.exists()
    return err


@pytest.fixture
def other_skeleton(tmp_path, clips):
    """A 3D clip of another skeleton (COCO-17 joint order), which body models cannot read."""
    target, _ = _resampled(clips["target"])
    return save_motion(Motion(target, 25.0, skeleton="coco-17"), tmp_path / "coco.npz")


@pytest.mark.parametrize("case", ["frame-too-large", "frame-negative", "source-too-short", "wrong-model",
                                  "baseline", "face-target", "face-model-body-clip", "other-skeleton",
                                  "reference-without-frames", "no-flow", "zero-samples", "bad-suffix",
                                  "negative-adapt-steps", "adapt-steps-with-samples"])
def test_bad_input(case, ckpts, clips, face_dir, other_skeleton, tmp_path, capsys):
    out, npz = tmp_path / "out.mp4", tmp_path / "out.npz"
    face = str(face_dir / "llv" / "dao.csv")
    base = ["transfer", "--model", str(ckpts["behavior"]), "--style", "skeleton", "--size", "32", "-o", str(out),
            "--npz", str(npz)]
    src = ["--behavior", clips["source"]]
    argv = {
        "frame-too-large": base + src + ["--target", clips["target"], "--target-frame", "100000"],
        "frame-negative": base + src + ["--target", clips["target"], "--target-frame", "-1"],
        "source-too-short": base + ["--behavior", clips["source"], "--behavior-start", "1000", "--target",
                                    clips["target"], "--horizon", "40"],
        "wrong-model": base[:2] + [str(ckpts["mtvae"])] + base[3:] + src + ["--target", clips["target"]],
        "baseline": base[:2] + ["zero-velocity"] + base[3:] + src + ["--target", clips["target"]],
        "face-target": base + src + ["--target", face],
        "face-model-body-clip": base[:2] + [str(ckpts["face"])] + base[3:] + ["--behavior", face, "--target",
                                                                               clips["target"]],
        "other-skeleton": base + src + ["--target", str(other_skeleton)],
        "reference-without-frames": base + src + ["--target", clips["target"], "--reference", clips["target"]],
        "no-flow": None,
        "zero-samples": base + ["--sample", "0", "--target", clips["target"]],
        "bad-suffix": base[:-4] + ["-o", str(tmp_path / "out.avi")] + src + ["--target", clips["target"]],
        "negative-adapt-steps": base + src + ["--target", clips["target"], "--adapt-steps", "-1"],
        "adapt-steps-with-samples": base + ["--sample", "2", "--target", clips["target"], "--adapt-steps", "10"],
    }[case]
    if case == "no-flow":
        bundle = load_model(ckpts["behavior"])
        bundle.model.flow_fitted.fill_(False)
        unfitted = save_checkpoint(tmp_path / "noflow.safetensors", model=bundle.model,
                                   meta=dataclasses.replace(bundle.meta))
        argv = base[:2] + [str(unfitted)] + base[3:] + ["--sample", "2", "--target", clips["target"]]
    err = _fails(argv, capsys, out, npz)
    expected = {"frame-too-large": "--target-frame 100000 is outside", "frame-negative": "--target-frame -1",
                "source-too-short": "behaviour source needs", "wrong-model": "'mtvae-add' model",
                "baseline": "baseline", "face-target": "face motion", "face-model-body-clip": "body motion",
                "other-skeleton": "coco-17", "reference-without-frames": "--style frames", "no-flow": "flow",
                "zero-samples": "--sample must be >= 1", "bad-suffix": "extension",
                "negative-adapt-steps": "--adapt-steps must be >= 0", "adapt-steps-with-samples": "--sample has none"}[case]
    assert expected in err


def test_a_reference_without_a_person_is_refused(ckpts, clips, tmp_path, capsys):
    """--style frames with a uniform reference image (a valid pose file beside it): one line naming the
    image, exit 2, no video and no npz."""
    import shutil

    from motion2video.formats.video import read_image

    demo = Path(__file__).resolve().parents[1] / "demo_inputs"
    image = read_image(demo / "reference_body_128.png")
    blank = tmp_path / "blank.png"
    write_image(blank, np.broadcast_to(image[0, 0], image.shape).copy())
    shutil.copy(demo / "reference_body_128.pose.npz", tmp_path / "blank.pose.npz")
    out, npz = tmp_path / "out.mp4", tmp_path / "out.npz"
    err = _fails(["transfer", "--model", str(ckpts["behavior"]), "--behavior", clips["source"], "--target",
                  clips["target"], "--style", "frames", "--reference", str(blank), "-o", str(out), "--npz", str(npz)],
                 capsys, out, npz)
    assert "blank.png" in err and "no visible person" in err


@pytest.mark.slow
def test_shipped_behavior_carries_held_out_jumps_kicks_and_speeds(mocap_dir, tmp_path, capsys):
    """The shipped checkpoint: on held-out subjects, re-enacted from other subjects' postures as ``motion2video
    transfer`` does it (the decoder fitted to the source retargeted onto each posture), the median signature
    ratio of jumps (pelvis excursion), kicks (ankle above the knee) and walks / runs (root speed) is within
    0.6-1.4, and so are the jumps' and kicks' root-relative signatures (leg extension, arm swing, knee bend, ankle
    lift: 0.98-1.30 when measured, docs/results.md; asserted from 0.55, which the decoder as trained
    misses on the kick by far: 0.23-0.41); the re-enactment starts at the target's posture and keeps its bone
    lengths; and the same numbers come out of ``transfer --npz`` (a hidden jump re-enacted by a hidden walker)."""
    from motion2video.evaluation import signatures as S
    from motion2video.evaluation import transfer_benchmark as B

    cases = tuple(c for c in B.CASES if c.split == "held-out" and c.behaviour in ("jump", "kick", "walk/run"))
    results = B.run_benchmark(str(mocap_dir), transfer=load_model("behavior"), cases=cases)
    for row in B.summarise(results):
        if row["method"] == "transfer":
            assert 0.6 <= row["median_ratio"] <= 1.4, row
            assert row["start_error"] < 0.04 and row["bone_spread"] < 1e-4, row
            if row["behaviour"] in ("jump", "kick"):
                assert all(0.55 <= v <= 1.4 for v in row["relative"].values()), row
    npz = tmp_path / "t.npz"
    assert main(["transfer", "--model", "behavior", "--behavior", str(mocap_dir / "cmu/02_04.bvh"),
                 "--target", str(mocap_dir / "cmu/07_03.bvh"), "--target-frame", "144", "--style", "skeleton",
                 "--size", "64", "-o", str(tmp_path / "t.mp4"), "--npz", str(npz)]) == 0
    kept = np.load(npz)
    ratio = S.pelvis_excursion(kept["reenacted"][0]) / S.pelvis_excursion(kept["source"])
    assert 0.6 <= ratio <= 1.4 and S.pelvis_excursion(kept["source"]) > 0.5
    for name in S.ROOT_RELATIVE_SIGNATURES:  # 1.04 / 1.01 / 1.05 / 1.04 when measured
        made, real = S.signature(name, kept["reenacted"][0], 25.0), S.signature(name, kept["source"], 25.0)
        assert 0.6 <= made / real <= 1.4, name


def test_the_decoder_is_fitted_to_the_source_retargeted_onto_the_target(ckpts, clips):
    """reenact_source fits the decoder to the source moved onto the target's posture and bones
    (core.retarget.retarget_motion), not to the source from its own start: with the steps of a fit the
    re-enactment comes closer to that goal (root-relative joints) than the decoder as trained."""
    from motion2video.core.retarget import retarget_motion
    from motion2video.stages.latents import BLEND_SECONDS, reenact_source

    bundle = load_model(ckpts["behavior"])
    source = load_clip(bundle, clips["source"]).data[40:40 + 1 + HORIZON]
    start = load_clip(bundle, clips["target"]).data[20]
    goal = retarget_motion(source, start, blend_frames=int(round(BLEND_SECONDS * 25)))

    def distance(steps):
        _, made, _ = reenact_source(bundle, source, start, adapt_steps=steps)
        np.testing.assert_allclose(made[0, 0], start, atol=1e-5)
        rel = lambda x: x - x[:, :1]  # noqa: E731
        return float(np.linalg.norm(rel(made[0, 1:]) - rel(goal[1:]), axis=-1).mean())

    assert distance(100) < 0.6 * distance(0)


@pytest.mark.slow
def test_shipped_behavior_carries_unseen_jumps_and_waves_from_a_walker(mocap_dir, shared_dir):
    """The shipped checkpoint, as ``transfer`` runs it (300 fitting steps), on sources no shipped model trained on:
    a CMU jump of a test subject from another test subject's walking posture, and a Bandai-Namco wave from a CMU
    walker. Every root-relative signature the source moves by 5 cm or more comes across at 0.6 or more of the
    source's (1.00-1.02 for the jump and 0.96 for the wave's arm swing when measured, docs/results.md "Transfer
    from any posture"; a decoder fitted to the source from the source's own start kept 0.29-0.39 of a jump's arm
    swing from another start)."""
    from motion2video.evaluation import signatures as S

    bundle = load_model("behavior")
    cases = ((mocap_dir / "cmu/02_04.bvh", 0, mocap_dir / "cmu/05_01.bvh", 200, S.ROOT_RELATIVE_SIGNATURES[:3]),
             (shared_dir / "data/bandai/bvh/dataset-2_wave-both-hands_feminine_001.bvh.xz", 0,
              mocap_dir / "cmu/07_03.bvh", 144, ("arm_swing",)))
    for source, source_start, target, target_frame, names in cases:
        result = transfer_behavior(bundle, load_clip(bundle, source), load_clip(bundle, target),
                                   source_start=source_start, target_frame=target_frame)
        for name in names:
            real = S.signature(name, result.source, 25.0)
            assert real >= 0.05, (source.name, name)
            assert S.signature(name, result.reenacted[0], 25.0) / real >= 0.6, (source.name, name)
