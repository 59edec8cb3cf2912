"""Frame generator: network, SSIM, checkpoints, training/resume, baselines, metrics, contact sheets.

These use the toy OpenCV dataset (generator.data.toy_sequences) and tiny configs; the rendered Anny data and
the CLI are exercised in test_frames_data.py.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from safetensors import safe_open
from skimage.metrics import structural_similarity

from motion2video.core.errors import InputError
from motion2video.generator.image_baselines import border_anchors, copy_reference, limb_warp, run_baseline
from motion2video.generator.checkpoint import (load_frame_model, resolve_model_path, save_frame_model,
                                            state_path)
from motion2video.generator.data import (
    BODY_STRUCTURE_CHANNELS, body_structures, evaluation_pair_index, make_pairs, sample_pair_index, toy_sequences,
)
from motion2video.generator.specs import identities
from motion2video.generator.scores import (METHODS, contact_sheet, evaluate_sequences, evaluation_contact_sheet,
                                          frame_metrics, write_json)
from motion2video.generator.model import (FrameGenerator, FrameGeneratorConfig, count_parameters, generate, ssim)
from motion2video.generator.training import TrainFramesConfig, train_frames
from motion2video.core.schedule import learning_rate
from motion2video.core.skeletons import H36M_17

TINY = dict(image_size=32, channels=(8, 12, 16))


def tiny_config(domain: str = "body") -> FrameGeneratorConfig:
    return FrameGeneratorConfig(domain=domain, structure_channels=BODY_STRUCTURE_CHANNELS if domain == "body" else 1,
                                **TINY)


def test_default_generator_is_small():
    model = FrameGenerator(FrameGeneratorConfig())
    n = count_parameters(model)
    assert 1_000_000 <= n <= 2_000_000, n
    assert n * 4 < 30 * 2**20  # float32 checkpoint under 30 MB


def test_config_validation_and_json_round_trip():
    cfg = FrameGeneratorConfig(domain="face", structure_channels=1, image_size=256)
    assert FrameGeneratorConfig.from_dict(json.loads(cfg.to_json())) == cfg
    with pytest.raises(ValueError):
        FrameGeneratorConfig(image_size=100)  # not a multiple of 16
    with pytest.raises(ValueError):
        FrameGeneratorConfig(domain="hand")
    with pytest.raises(ValueError):
        FrameGeneratorConfig.from_dict({"nope": 1})


def test_residual_generator_starts_as_copy_reference():
    torch.manual_seed(0)
    model = FrameGenerator(tiny_config())
    x = torch.rand(2, 3, 32, 32)
    p = torch.rand(2, BODY_STRUCTURE_CHANNELS, 32, 32)
    q = torch.rand(2, BODY_STRUCTURE_CHANNELS, 32, 32)
    assert torch.equal(model(x, p, q), x)
    direct = FrameGenerator(FrameGeneratorConfig(output="direct", **TINY))
    y = direct(x, p, q)
    assert y.shape == (2, 3, 32, 32) and float(y.detach().min()) >= 0.0 and float(y.detach().max()) <= 1.0


def test_ssim_matches_scikit_image_gaussian_ssim():
    rng = np.random.default_rng(0)
    a = rng.random((40, 48, 3))
    b = np.clip(a + rng.normal(0, 0.1, a.shape), 0, 1)
    ref = structural_similarity(a, b, channel_axis=-1, data_range=1.0, gaussian_weights=True, sigma=1.5,
                                use_sample_covariance=False)
    ta = torch.from_numpy(a).permute(2, 0, 1)[None]
    tb = torch.from_numpy(b).permute(2, 0, 1)[None]
    ours = float(ssim(ta, tb)[0])
    assert ours == pytest.approx(ref, abs=1e-6)
    assert float(ssim(ta, ta)[0]) == pytest.approx(1.0, abs=1e-9)


def test_generate_uint8_batches_and_shape_checks():
    model = FrameGenerator(tiny_config())
    seqs = toy_sequences("body", num_sequences=2, frames_per_sequence=3, image_size=32)
    pairs = make_pairs(seqs, evaluation_pair_index(seqs))
    out = generate(model, pairs.ref_images, pairs.ref_structures, pairs.tgt_structures, batch_size=3)
    assert out.dtype == np.uint8 and out.shape == pairs.ref_images.shape
    np.testing.assert_array_equal(out, pairs.ref_images)  # zero-initialised residual head
    with pytest.raises(ValueError):
        generate(model, pairs.ref_images[:, :16], pairs.ref_structures, pairs.tgt_structures)


@pytest.mark.parametrize("factor", [2, 4])
def test_pooled_structures_are_the_full_maps_averaged(factor):
    """What the mesh generator's network reads, built small, is the full-size maps averaged over its blocks."""
    import torch.nn.functional as F

    from motion2video.generator.data import pooled_body_structures

    points = np.random.default_rng(3).uniform(-8, 72, (4, 17, 2))
    points[1, 5] = np.nan  # a joint not found: its heatmap is empty, its limbs not drawn
    full = torch.from_numpy(body_structures(points, 64))
    small = pooled_body_structures(points, 64, factor)
    assert small.shape == (4, BODY_STRUCTURE_CHANNELS, 64 // factor, 64 // factor) and small.dtype == np.float32
    np.testing.assert_allclose(small, F.avg_pool2d(full, factor).numpy(), atol=1e-6)
    assert small[1, 5].max() == 0 and small.max() > 0.5
    np.testing.assert_array_equal(pooled_body_structures(points, 64, 1), full.numpy())


def test_body_structures_and_flip_keep_joint_meaning():
    seqs = toy_sequences("body", num_sequences=2, frames_per_sequence=3, image_size=32)
    st = body_structures(seqs.points[0], 32)
    assert st.shape == (3, BODY_STRUCTURE_CHANNELS, 32, 32) and st.dtype == np.float32
    # The peak of heatmap j sits on joint j.
    j = H36M_17.index("left_wrist")
    y, x = np.unravel_index(np.argmax(st[0, j]), (32, 32))
    assert abs(x + 0.5 - seqs.points[0, 0, j, 0]) <= 1.0 and abs(y + 0.5 - seqs.points[0, 0, j, 1]) <= 1.0
    index = np.array([[0, 0, 1]])
    plain = make_pairs(seqs, index)
    flipped = make_pairs(seqs, index, flip=np.array([True]))
    np.testing.assert_array_equal(flipped.ref_images[0], plain.ref_images[0, :, ::-1])
    # After mirroring, the left-wrist channel holds the mirrored right wrist.
    r = H36M_17.index("right_wrist")
    np.testing.assert_allclose(flipped.ref_points[0, j, 0], 32 - plain.ref_points[0, r, 0])
    np.testing.assert_allclose(flipped.ref_structures[0, j], plain.ref_structures[0, r, :, ::-1], atol=1e-5)


def test_pair_sampling_never_pairs_a_frame_with_itself():
    seqs = toy_sequences("body", num_sequences=3, frames_per_sequence=4, image_size=32)
    index = sample_pair_index(np.random.default_rng(0), seqs, 500)
    assert np.all(index[:, 1] != index[:, 2])
    assert index[:, 0].max() < 3 and index[:, 1:].max() < 4
    fixed = evaluation_pair_index(seqs)
    assert len(fixed) == 3 * 3 and np.all(fixed[:, 1] == 0)


def test_identity_splits_are_disjoint_and_reproducible():
    train, test = identities("train", 5), identities("test", 5)
    assert identities("train", 5) == train
    assert not set(train) & set(test)


def test_checkpoint_round_trip_and_errors(tmp_path):
    torch.manual_seed(1)
    model = FrameGenerator(tiny_config("face"))
    with torch.no_grad():
        model.decoder.head.weight.normal_(0, 0.1)
    path = save_frame_model(model, tmp_path / "m.safetensors", step=7, train={"note": "x"})
    with safe_open(str(path), framework="pt") as f:
        meta = f.metadata()
    assert meta["format"] == "motion2video-frames" and json.loads(meta["config"])["domain"] == "face"
    loaded = load_frame_model(path)
    assert loaded.step == 7 and loaded.train == {"note": "x"} and loaded.config == model.config
    x, p, q = torch.rand(1, 3, 32, 32), torch.rand(1, 1, 32, 32), torch.rand(1, 1, 32, 32)
    model.eval()
    torch.testing.assert_close(loaded.model(x, p, q), model(x, p, q))
    bad = tmp_path / "bad.safetensors"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(InputError, match="bad.safetensors"):
        load_frame_model(bad)
    with pytest.raises(InputError, match="no such checkpoint"):
        resolve_model_path("frames-nonexistent-128")


def test_learning_rate_schedule():
    cfg = TrainFramesConfig(steps=100, warmup_steps=10, lr=1e-3, final_lr_fraction=0.1)
    assert learning_rate(0, cfg) == pytest.approx(1e-4)
    assert learning_rate(9, cfg) == pytest.approx(1e-3)
    assert learning_rate(99, cfg) == pytest.approx(1e-4, rel=0.05)
    assert all(learning_rate(s, cfg) >= learning_rate(s + 1, cfg) for s in range(10, 99))


@pytest.mark.slow
def test_training_lowers_the_loss(tmp_path):
    # Two frames of one sequence: the generator must learn to move the puppet (it starts as copy-reference).
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=2, image_size=32)
    cfg = TrainFramesConfig(steps=60, batch_size=2, lr=3e-3, warmup_steps=5, log_every=5, checkpoint_every=30,
                            flip=False)
    result = train_frames(seqs, output=tmp_path / "full.safetensors", config=cfg, model_config=tiny_config(),
                          progress=False)
    first = np.mean([h["loss"] for h in result.history[:2]])
    last = np.mean([h["loss"] for h in result.history[-2:]])
    assert last < 0.8 * first, result.history
    assert result.steps == 60 and result.steps_per_second > 0
    assert load_frame_model(result.path).step == 60 and state_path(result.path).is_file()


class Interrupt(Exception):
    pass


@pytest.mark.slow
def test_resume_continues_an_interrupted_run_exactly(tmp_path, monkeypatch):
    import motion2video.generator.training as train_mod

    seqs = toy_sequences("body", num_sequences=6, frames_per_sequence=4, image_size=32)
    cfg = TrainFramesConfig(steps=12, batch_size=4, warmup_steps=3, log_every=3, checkpoint_every=6)
    one = train_frames(seqs, output=tmp_path / "one.safetensors", config=cfg, model_config=tiny_config(),
                       progress=False)
    # Crash a second run right after its step-6 checkpoint (step 7's batch raises), as a kill would.
    original = train_mod.sample_pair_index
    calls = {"n": 0}

    def crashing(rng, s, b):
        calls["n"] += 1
        if calls["n"] == 7:
            raise Interrupt
        return original(rng, s, b)

    with monkeypatch.context() as m:
        m.setattr(train_mod, "sample_pair_index", crashing)
        with pytest.raises(Interrupt):
            train_frames(seqs, output=tmp_path / "two.safetensors", config=cfg, model_config=tiny_config(),
                         progress=False)
    assert load_frame_model(tmp_path / "two.safetensors").step == 6
    two = train_frames(seqs, output=tmp_path / "two.safetensors", config=cfg, resume=True, progress=False)
    assert two.steps == 12
    a = load_frame_model(one.path).model.state_dict()
    b = load_frame_model(two.path).model.state_dict()
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("points", [17, 470], ids=["body joints", "face landmarks"])
def test_limb_warp_is_scikit_images_piecewise_affine_warp(points):
    """The same pixels as scikit-image's PiecewiseAffineTransform and warp (bilinear, the border's pixels beyond
    it) over the same control points: the body's 17 joints, a tracked face's 470 landmarks."""
    from skimage.transform import PiecewiseAffineTransform, warp

    from motion2video.generator.image_baselines import _select_points

    rng = np.random.default_rng(points)
    img = (rng.random((96, 96, 3)) * 255).astype(np.uint8)
    ref = rng.uniform(4, 92, (points, 2))
    tgt = ref + rng.normal(0, 3, ref.shape)
    src_ref, src_tgt = _select_points(ref, tgt, border_anchors(96, 96), width=96, height=96)
    tform = PiecewiseAffineTransform.from_estimate(src_tgt - 0.5, src_ref - 0.5)
    expected = np.clip(np.rint(warp(img, tform, order=1, mode="edge", preserve_range=True)), 0, 255).astype(np.uint8)
    np.testing.assert_array_equal(limb_warp(img, ref, tgt), expected)


def test_copy_reference_and_limb_warp_geometry():
    rng = np.random.default_rng(0)
    img = (rng.random((48, 48, 3)) * 255).astype(np.uint8)
    pts = rng.uniform(8, 40, (17, 2))
    np.testing.assert_array_equal(copy_reference(img), img)
    np.testing.assert_array_equal(limb_warp(img, pts, pts), img)  # no motion, no change
    # Moving a grid of control points by (+3, +2) pixels moves the content inside the grid by the same.
    grid = np.stack(np.meshgrid(np.linspace(8, 40, 5), np.linspace(8, 40, 5)), -1).reshape(-1, 2)
    moved = limb_warp(img, grid, grid + np.array([3.0, 2.0]))
    np.testing.assert_array_equal(moved[14:38, 13:37], img[12:36, 10:34])
    # Coincident and far-away points are tolerated.
    bad = pts.copy()
    bad[1] = bad[0]
    bad[5] = (500.0, -300.0)
    assert limb_warp(img, bad, bad + 1.0).shape == img.shape
    assert border_anchors(48, 48).shape == (16, 2)
    with pytest.raises(ValueError):
        run_baseline("nearest-neighbour", img[None], pts[None], pts[None])


@pytest.mark.filterwarnings("ignore:divide by zero")
def test_frame_metrics_use_scikit_image_conventions():
    rng = np.random.default_rng(0)
    a = (rng.random((2, 32, 32, 3)) * 255).astype(np.uint8)
    b = a.copy()
    b[1, :4] = 0
    psnr, s = frame_metrics(b, a)
    assert np.isinf(psnr[0]) and s[0] == pytest.approx(1.0)
    mse = np.mean((a[1].astype(float) - b[1]) ** 2)
    assert psnr[1] == pytest.approx(10 * np.log10(255**2 / mse))
    with pytest.raises(ValueError):
        frame_metrics(a.astype(np.float32), a)


@pytest.mark.parametrize("domain", ["body", "face"])
def test_evaluation_json_shape_and_contact_sheet(tmp_path, domain):
    seqs = toy_sequences(domain, num_sequences=2, frames_per_sequence=3, image_size=32)
    model = FrameGenerator(tiny_config(domain))
    ev = evaluate_sequences(model, seqs)
    assert ev.num_pairs == 4 and set(ev.results) == set(METHODS)
    # The untrained residual generator is exactly copy-reference.
    assert ev.results["generator"].psnr == pytest.approx(ev.results["copy-reference"].psnr)
    out = write_json(ev, tmp_path / "eval.json")
    payload = json.loads(out.read_text())
    person = {"person_psnr", "person_ssim", "person_sharpness", "moving_psnr", "moving_sharpness"}
    for method in METHODS:
        assert set(payload["results"][method]) == {"psnr", "ssim", "head_psnr", "head_ssim"} | person
        # Held-out pairs carry no head masks: the head keys are there, and null.
        assert payload["results"][method]["head_psnr"] is None and payload["results"][method]["head_ssim"] is None
    # The toy data has silhouettes, so the person targets are reported.
    assert set(payload["targets_met"]) == {"person_psnr_vs_limb_warp_3db", "person_psnr_vs_copy_reference_5db",
                                           "person_sharpness_0.9", "psnr_29db", "ssim_above_every_baseline"}
    sheet = evaluation_contact_sheet(ev, rows=3)
    assert sheet.dtype == np.uint8 and sheet.shape == (18 + 3 * 34, 5 * 34, 3)
    with pytest.raises(ValueError):
        contact_sheet({"a": seqs.images[0], "b": seqs.images[0, :, :16]})


def test_head_metrics_known_answers():
    """With the whole silhouette as the "head", the head metrics equal the person metrics; a prediction wrong
    only outside the head scores ~148 dB (the 1e-10 MSE floor) there, and one wrong by a known amount inside
    it scores the known PSNR."""
    seqs = toy_sequences("body", num_sequences=2, frames_per_sequence=3, image_size=32)
    ev = evaluate_sequences(None, seqs, head_masks=seqs.masks)
    for scores in ev.results.values():
        assert scores.person["head_psnr"] == pytest.approx(scores.person["person_psnr"])
        assert scores.person["head_ssim"] == pytest.approx(scores.person["person_ssim"])
    from motion2video.generator.scores import person_metrics

    target = seqs.images[:, 1]
    head = np.zeros(target.shape[:3], bool)
    head[:, 4:10, 12:20] = True
    outside = target.copy()
    outside[~head] = 255 - outside[~head]
    per = person_metrics(outside, target, seqs.images[:, 0], seqs.masks[:, 0], seqs.masks[:, 1], head)
    assert np.all(per["head_psnr"] > 140) and np.all(per["head_psnr"] > per["person_psnr"])
    inside = target.astype(np.int16)
    inside[head] = np.clip(inside[head] + np.where(inside[head] < 128, 16, -16), 0, 255)
    per = person_metrics(inside.astype(np.uint8), target, seqs.images[:, 0], seqs.masks[:, 0], seqs.masks[:, 1],
                         head)
    np.testing.assert_allclose(per["head_psnr"], 10 * np.log10(255**2 / 16**2))
    assert np.all(per["head_ssim"] < 1.0)
    empty = person_metrics(target, target, seqs.images[:, 0], seqs.masks[:, 0], seqs.masks[:, 1],
                           np.zeros_like(head))
    assert np.all(np.isnan(empty["head_psnr"])) and np.all(np.isnan(empty["head_ssim"]))


def test_training_crops_hold_both_poses():
    from motion2video.generator.data import crop_origins

    seqs = toy_sequences("body", num_sequences=3, frames_per_sequence=3, image_size=32)
    index = sample_pair_index(np.random.default_rng(1), seqs, 6)
    pairs = make_pairs(seqs, index)
    origins = crop_origins(np.random.default_rng(2), pairs.ref_points, pairs.tgt_points, size=32, crop=16)
    assert origins.shape == (6, 2) and origins.min() >= 0 and origins.max() <= 16
    cropped = make_pairs(seqs, index, crop=16, rng=np.random.default_rng(2))
    assert cropped.ref_images.shape == (6, 16, 16, 3) and cropped.tgt_structures.shape == (6, 33, 16, 16)
    x0, y0 = origins[0]
    np.testing.assert_array_equal(cropped.tgt_images[0], pairs.tgt_images[0, y0:y0 + 16, x0:x0 + 16])
    np.testing.assert_allclose(cropped.ref_points[0], pairs.ref_points[0] - origins[0])
    np.testing.assert_allclose(cropped.tgt_structures[0], body_structures(cropped.tgt_points[:1], 16)[0])
    # Points that fit in a crop stay inside it.
    small = np.full((1, 17, 2), 10.0) + np.linspace(0, 5, 17)[None, :, None]
    o = crop_origins(np.random.default_rng(3), small, small + 3, size=32, crop=16)
    assert np.all(small - o[:, None] >= 0) and np.all(small + 3 - o[:, None] <= 16)
    face = toy_sequences("face", num_sequences=2, frames_per_sequence=2, image_size=32)
    assert make_pairs(face, [[0, 0, 1]], crop=16, rng=np.random.default_rng(0)).ref_structures.shape == (1, 1, 16, 16)
