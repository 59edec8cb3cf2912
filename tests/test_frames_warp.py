"""The warping body generator (motion2video.generator.warp), the person metrics and the checkpoint kinds.

Toy OpenCV puppets (generator.data.toy_sequences) and tiny configs; the rendered data and the shipped weights
are exercised by tests/test_frames_data.py and the evaluate-frames run of docs/results.md.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motion2video.core.errors import InputError
from motion2video.generator.checkpoint import load_frame_model, save_frame_model
from motion2video.generator.data import body_structures, evaluation_pair_index, make_pairs, toy_sequences
from motion2video.generator.scores import (evaluate_sequences, gradient_energy, person_metrics, region_psnr,
                                          sharpness_ratio)
from motion2video.generator.model import FrameGenerator, FrameGeneratorConfig
from motion2video.generator.training import TrainFramesConfig, train_frames
from motion2video.generator.warp import (NUM_COMPONENTS, WarpGenerator, WarpGeneratorConfig, part_logits, part_maps,
                                      person_crop, pixel_centres, warp_generate)


def toy_pose(size: int = 64) -> np.ndarray:
    from motion2video.generator.data import _TOY_REST

    return (size / 2 + _TOY_REST * 0.8 * size).astype(np.float32)  # (17, 2)


def test_part_maps_follow_the_joints():
    ref = torch.from_numpy(toy_pose())[None]
    pix = pixel_centres(64, 64)
    # Same pose: every part maps each pixel to itself.
    same = part_maps(ref, ref, 64, 64)
    assert same.shape == (1, NUM_COMPONENTS, 64, 64, 2)
    torch.testing.assert_close(same, pix[None, None].expand_as(same), atol=1e-3, rtol=0)
    # The target is the reference moved by (5, -3): every part samples the reference 5 px left, 3 px down.
    shift = torch.tensor([5.0, -3.0])
    moved = part_maps(ref, ref + shift, 64, 64)
    torch.testing.assert_close(moved[:, :-1], (pix - shift)[None, None].expand_as(moved[:, :-1]), atol=1e-3,
                               rtol=0)
    torch.testing.assert_close(moved[:, -1], pix[None])  # the background stays
    # The right forearm turned by 90 degrees about the elbow: its end maps back to the reference wrist.
    tgt = ref.clone()
    elbow, wrist = ref[0, 15], ref[0, 16]
    v = wrist - elbow
    tgt[0, 16] = elbow + torch.stack([-v[1], v[0]])
    maps = part_maps(ref, tgt, 64, 64)
    k = 1 + [n for n, _, _ in __import__("motion2video.generator.warp", fromlist=["SEGMENT_PARTS"]).SEGMENT_PARTS
             ].index("right_forearm")
    x, y = tgt[0, 16].tolist()
    j, i = int(x), int(y)  # the pixel holding the new wrist
    np.testing.assert_allclose(maps[0, k, i, j].numpy(), (wrist + (pix[i, j] - tgt[0, 16])
                               @ torch.tensor([[0.0, -1.0], [1.0, 0.0]])).numpy(), atol=1e-3)


def test_part_logits_put_parts_on_the_body_and_background_elsewhere():
    pts = torch.from_numpy(toy_pose())[None]
    logits = part_logits(pts, 64, 64)
    winner = logits.argmax(1)[0]  # (64, 64)
    assert winner[0, 0] == NUM_COMPONENTS - 1  # a corner is background
    x, y = ((pts[0, 0] + pts[0, 8]) / 2).tolist()  # the middle of the spine is torso
    assert winner[int(y), int(x)] == 0


def test_untrained_warp_generator_moves_the_person_and_keeps_the_background():
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=2, image_size=64)
    img = seqs.images[0, 0]
    pts = seqs.points[0, 0]
    # A target that is the reference frame shifted right by 6 px (background included, so the whole
    # truth is known) and a target pose shifted with it.
    shifted = np.roll(img, 6, axis=1)
    model = WarpGenerator(WarpGeneratorConfig(image_size=64))
    out = warp_generate(model, img[None], pts[None], (pts + [6.0, 0.0])[None])[0]
    person = seqs.masks[0, 0]
    moved_person = np.roll(person, 6, axis=1)
    err_person = np.abs(out.astype(int) - shifted)[moved_person].mean()
    err_copy = np.abs(img.astype(int) - shifted)[moved_person].mean()
    assert err_person < 0.35 * err_copy  # the person moved with the pose
    # Pixels far (> 16 px) from every joint of both poses are the reference's, exactly.
    yy, xx = np.mgrid[0:64, 0:64] + 0.5
    joints = np.concatenate([pts, pts + [6.0, 0.0]])
    dist = np.min(np.hypot(xx[..., None] - joints[:, 0], yy[..., None] - joints[:, 1]), axis=-1)
    far = dist > 16
    assert far.sum() > 500
    np.testing.assert_array_equal(out[far], img[far])


def test_warp_generator_trains_saves_and_loads(tmp_path):
    seqs = toy_sequences("body", num_sequences=3, frames_per_sequence=3, image_size=32)
    cfg = TrainFramesConfig(steps=3, batch_size=2, checkpoint_every=3, log_every=1, model_kind="warp",
                            edge_weight=1.0, person_weight=2.0)
    result = train_frames(seqs, output=tmp_path / "w.safetensors", config=cfg, progress=False)
    assert result.steps == 3 and {"person_l1", "person_edge"} <= set(result.history[-1])
    loaded = load_frame_model(result.path)
    assert loaded.kind == "warp" and isinstance(loaded.model, WarpGenerator)
    assert loaded.train["model_kind"] == "warp"
    # The loaded weights give the frames the trained model gives.
    pairs = make_pairs(seqs, evaluation_pair_index(seqs)[:2])
    model = WarpGenerator(loaded.config)
    model.load_state_dict(loaded.model.state_dict())
    np.testing.assert_array_equal(warp_generate(loaded.model, pairs.ref_images, pairs.ref_points, pairs.tgt_points),
                                  warp_generate(model, pairs.ref_images, pairs.ref_points, pairs.tgt_points))
    # Old checkpoints (no kind in the metadata) still load as analogy generators.
    old = save_frame_model(FrameGenerator(FrameGeneratorConfig(image_size=32, channels=(4, 8))),
                           tmp_path / "a.safetensors", step=0)
    assert load_frame_model(old).kind == "analogy"


def test_decode_pastes_into_a_full_resolution_reference():
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=2, image_size=64)
    model = WarpGenerator(WarpGeneratorConfig(image_size=32))
    # A 64 px reference through a 32 px model: the person is generated at 32 px, the rest stays exact.
    state = model.encode_reference(seqs.images[0, 0], seqs.points[0, 0])
    frames = model.decode(state, seqs.points[0, :2])
    assert frames.shape == (2, 64, 64, 3) and frames.dtype == np.uint8
    x0, y0, side = person_crop(seqs.points[0, 0], seqs.points[0, :2], width=64, height=64, model_size=32)
    outside = np.ones((64, 64), bool)
    outside[y0:y0 + side, x0:x0 + side] = False
    np.testing.assert_array_equal(frames[1][outside], seqs.images[0, 0][outside])


@pytest.mark.parametrize("change, message", [
    (lambda p: p + [1000.0, 0.0], "outside"),
    (lambda p: np.full_like(p, np.nan), "not finite"),
    (lambda p: np.full_like(p, 10.0), "no visible person"),
])
def test_bad_references_are_refused(change, message):
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=1, image_size=64)
    model = WarpGenerator(WarpGeneratorConfig(image_size=32))
    with pytest.raises(InputError, match=message):
        model.encode_reference(seqs.images[0, 0], change(seqs.points[0, 0].astype(np.float64)))


def test_a_uniform_reference_image_shows_no_person():
    """Joints that are fine on an image that is one colour along every limb: no person to move."""
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=1, image_size=64)
    model = WarpGenerator(WarpGeneratorConfig(image_size=32))
    image = seqs.images[0, 0]
    blank = np.empty_like(image)
    blank[:] = image[0, 0]  # the backdrop's colour everywhere
    with pytest.raises(InputError, match="no visible person where its pose is"):
        model.encode_reference(blank, seqs.points[0, 0])
    model.encode_reference(image, seqs.points[0, 0])  # the same pose on the real image is accepted


def test_an_empty_crop_is_refused():
    seqs = toy_sequences("body", num_sequences=1, frames_per_sequence=1, image_size=64)
    model = WarpGenerator(WarpGeneratorConfig(image_size=32))
    state = model.encode_reference(seqs.images[0, 0], seqs.points[0, 0])
    with pytest.raises(InputError, match="crop is empty"):
        model.decode(state, seqs.points[0, 0] + [-500.0, 0.0])  # every target joint far outside
    with pytest.raises(InputError, match="crop is empty"):
        person_crop(np.full((17, 2), -50.0), np.full((1, 17, 2), -60.0), width=64, height=64, model_size=32)


def test_person_metrics():
    rng = np.random.default_rng(0)
    truth = rng.integers(0, 256, (1, 32, 32, 3), dtype=np.uint8)
    mask = np.zeros((1, 32, 32), bool)
    mask[0, 8:24, 8:24] = True
    import cv2

    blurred = cv2.GaussianBlur(truth[0], (0, 0), 1.5)[None]
    assert sharpness_ratio(truth[0], truth[0], mask[0]) == pytest.approx(1.0)
    assert sharpness_ratio(blurred[0], truth[0], mask[0]) < 0.5
    assert gradient_energy(np.full((8, 8, 3), 7, np.uint8)).max() == 0
    off = truth.copy()
    off[0, 8:24, 8:24] = np.clip(off[0, 8:24, 8:24].astype(int) + 20, 0, 255)
    mse = ((off[0].astype(float) - truth[0]) ** 2)[mask[0]].mean()
    assert region_psnr(off[0], truth[0], mask[0]) == pytest.approx(10 * np.log10(255**2 / mse))
    # A moved region is where reference and target differ inside either silhouette.
    per = person_metrics(off, truth, off, mask, mask)
    assert per["person_psnr"][0] == pytest.approx(per["moving_psnr"][0], abs=0.3)
    assert np.isnan(region_psnr(off[0], truth[0], np.zeros((32, 32), bool)))


def test_evaluation_scores_a_named_baseline_generator():
    seqs = toy_sequences("body", num_sequences=2, frames_per_sequence=3, image_size=32)
    warp = WarpGenerator(WarpGeneratorConfig(image_size=32))
    old = FrameGenerator(FrameGeneratorConfig(image_size=32, channels=(4, 8)))
    ev = evaluate_sequences(warp, seqs, baseline_models={"frames-body-128-v1": old})
    assert set(ev.results) == {"generator", "copy-reference", "limb-warp", "frames-body-128-v1"}
    # The untrained residual analogy generator is copy-reference, on the person metrics too.
    assert ev.results["frames-body-128-v1"].person == pytest.approx(ev.results["copy-reference"].person,
                                                                    nan_ok=True)
    assert "person_psnr_vs_frames-body-128-v1_2db" in ev.targets_met()
    assert body_structures(seqs.points[0], 32).shape == (3, 33, 32, 32)


def train_then_init_from(tmp_path, seqs, first: WarpGeneratorConfig, second: WarpGeneratorConfig, *,
                         first_steps: int = 1):
    """Train a warp model with ``first`` for ``first_steps``, then one step of a ``second`` model started from
    it (--init-from) at lr 1e-12, which keeps the carried weights; returns both training results."""
    cfg = TrainFramesConfig(steps=first_steps, batch_size=2, checkpoint_every=first_steps, log_every=1,
                            model_kind="warp")
    a = train_frames(seqs, output=tmp_path / "a.safetensors", config=cfg, progress=False, model_config=first)
    b = train_frames(seqs, output=tmp_path / "b.safetensors", config=TrainFramesConfig(
        steps=1, batch_size=2, checkpoint_every=1, log_every=1, model_kind="warp", lr=1e-12), progress=False,
        model_config=second, init_from=a.path)
    return a, b


def test_init_from_carries_weights_across_net_scales(tmp_path):
    seqs = toy_sequences("body", num_sequences=3, frames_per_sequence=3, image_size=32)
    cfg = TrainFramesConfig(steps=1, batch_size=2, checkpoint_every=1, log_every=1, model_kind="warp")
    first, second = train_then_init_from(tmp_path, seqs, WarpGeneratorConfig(image_size=32, net_scale=4),
                                         WarpGeneratorConfig(image_size=32, net_scale=2))
    a, b = load_frame_model(first.path), load_frame_model(second.path)
    assert b.config.net_scale == 2 and b.train["init_from"] == str(first.path)
    for key, value in a.model.state_dict().items():  # a step at lr 1e-12 keeps the carried weights
        torch.testing.assert_close(b.model.state_dict()[key], value, atol=1e-6, rtol=0)
    old = save_frame_model(FrameGenerator(FrameGeneratorConfig(image_size=32, channels=(4, 8))),
                           tmp_path / "old.safetensors", step=0)
    with pytest.raises(InputError, match="cannot start from a analogy model"):
        train_frames(seqs, output=tmp_path / "c.safetensors", config=cfg, progress=False, init_from=old)


def test_flow_correction_grows_from_a_trained_model_and_starts_where_it_was(tmp_path):
    """--init-from a model without the flow residual into one with it: the trained weights carry over, the
    two new output channels start at zero, so the residual is zero; a non-zero residual moves the person."""
    seqs = toy_sequences("body", num_sequences=3, frames_per_sequence=3, image_size=32)
    first, second = train_then_init_from(
        tmp_path, seqs, WarpGeneratorConfig(image_size=32, net_scale=2),
        WarpGeneratorConfig(image_size=32, net_scale=2, flow_correction=True), first_steps=2)
    a, b = load_frame_model(first.path).model, load_frame_model(second.path).model
    assert b.config.flow_correction and not a.config.flow_correction
    head_a, head_b = a.decoder.head.weight, b.decoder.head.weight
    assert head_b.shape[0] == head_a.shape[0] + 2
    torch.testing.assert_close(head_b[: head_a.shape[0]], head_a, atol=1e-6, rtol=0)
    assert float(head_b[head_a.shape[0]:].detach().abs().max()) < 1e-6
    pairs = make_pairs(seqs, evaluation_pair_index(seqs)[:2])
    args = (torch.from_numpy(pairs.ref_images).permute(0, 3, 1, 2).float() / 255, torch.from_numpy(pairs.ref_points),
            torch.from_numpy(pairs.tgt_points), torch.from_numpy(pairs.tgt_structures))
    with torch.no_grad():
        out_a, out_b = a.forward_parts(*args), b.forward_parts(*args)
        torch.testing.assert_close(out_b.flow, out_a.flow, atol=1e-4, rtol=0)
        torch.testing.assert_close(out_b.image, out_a.image, atol=1e-4, rtol=0)
        b.decoder.head.bias[head_a.shape[0]] = 1.0  # a residual of one unit (32 / 32 = 1 px) to the right
        moved = b.forward_parts(*args)
    person = 1.0 - out_b.masks[:, -1]
    shift = (moved.flow - out_b.flow)[..., 0][person > 0.5]
    torch.testing.assert_close(shift, torch.ones_like(shift), atol=1e-4, rtol=0)


def test_bicubic_sampling_keeps_the_texture_sharper():
    """The same half-pixel shift of a random texture: bicubic sampling keeps more gradient energy than
    bilinear (which low-passes at sub-pixel offsets)."""
    from motion2video.generator.warp import warp_image

    rng = np.random.default_rng(0)
    image = torch.from_numpy(rng.random((1, 3, 32, 32))).float()
    flow = pixel_centres(32, 32)[None] + torch.tensor([0.5, 0.5])
    energy = {}
    for mode in ("bilinear", "bicubic"):
        out = (warp_image(image, flow, mode).clamp(0, 1)[0].permute(1, 2, 0).numpy() * 255).astype(np.uint8)
        energy[mode] = float(gradient_energy(out)[4:-4, 4:-4].mean())
    assert energy["bicubic"] > 1.3 * energy["bilinear"]
    with pytest.raises(ValueError, match="sample_mode"):
        WarpGeneratorConfig(image_size=32, sample_mode="nearest")
