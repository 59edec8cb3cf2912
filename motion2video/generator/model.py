"""The keypoint-conditioned frame generator (in the spirit of Villegas et al. 2017, the generator MT-VAE uses).

Given a reference frame ``x_ref``, its structure ``p_ref`` and a target structure ``p_tgt``, the network
makes the target frame by feature analogy::

    h_l = enc_img_l(x_ref) + enc_pose_l(p_tgt) - enc_pose_l(p_ref)        at every encoder level l

and decodes the bottleneck ``h_L`` with U-Net skip connections that carry the analogy features ``h_l`` of the
reference encoder. With ``output="residual"`` (default) the decoder predicts a change to the reference frame,
``x_ref + delta`` with the last layer zero-initialised, so training starts from copy-reference and what
does not move (the background) stays exact; ``output="direct"`` decodes the RGB frame itself. (A
mask-composite ``m * x_ref + (1 - m) * rgb`` was tried first: its mask saturated at 1 within a hundred steps
and the generator stayed a copy of the reference.)

Structures are maps of ``structure_channels`` channels at the image size: Gaussian heatmaps plus limb maps
for bodies, the rendered shaded face mesh for faces (see :mod:`motion2video.generator.data`).

Images entering and leaving the network are float tensors in [0, 1], (B, 3, H, W). No pretrained parts.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

DOMAINS = ("body", "face")
OUTPUTS = ("residual", "direct")


@dataclass(frozen=True)
class FrameGeneratorConfig:
    """Architecture of a frame generator.

    Attributes:
        domain: ``"body"`` or ``"face"``; decides how structures are made (see generator.data).
        image_size: square frame size in pixels (128 default, 256 configurable); a multiple of 2**levels.
        structure_channels: channels of a structure map (body: heatmaps + limb maps; face: 1 shaded grey).
        channels: feature channels per encoder level, level 0 at full resolution; len(channels) - 1
            down-samplings.
        output: ``"residual"`` (reference + decoded change) or ``"direct"`` (decoded RGB only).
    """

    domain: str = "body"
    image_size: int = 128
    structure_channels: int = 33
    channels: tuple[int, ...] = (16, 32, 64, 96, 128)
    output: str = "residual"

    def __post_init__(self) -> None:
        if self.domain not in DOMAINS:
            raise ValueError(f"domain must be one of {DOMAINS}, got {self.domain!r}")
        if self.output not in OUTPUTS:
            raise ValueError(f"output must be one of {OUTPUTS}, got {self.output!r}")
        if len(self.channels) < 2:
            raise ValueError("channels needs at least two levels")
        factor = 2 ** (len(self.channels) - 1)
        if self.image_size < factor or self.image_size % factor:
            raise ValueError(f"image_size {self.image_size} must be a positive multiple of {factor}")
        if self.structure_channels < 1:
            raise ValueError("structure_channels must be >= 1")

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_dict(cls, values: dict) -> "FrameGeneratorConfig":
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = set(values) - known
        if unknown:
            raise ValueError(f"FrameGeneratorConfig has no field(s) {sorted(unknown)}")
        values = dict(values)
        if "channels" in values:
            values["channels"] = tuple(int(c) for c in values["channels"])
        return cls(**values)


def _conv(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    """3x3 convolution + LeakyReLU(0.2)."""
    return nn.Sequential(nn.Conv2d(cin, cout, 3, stride=stride, padding=1), nn.LeakyReLU(0.2, inplace=True))


class Encoder(nn.Module):
    """A conv pyramid: level 0 at full resolution, each further level halves it.

    forward(x (B, C, H, W)) -> list of features [(B, channels[l], H / 2**l, W / 2**l) for each level l].
    """

    def __init__(self, in_channels: int, channels: tuple[int, ...]) -> None:
        super().__init__()
        levels = [nn.Sequential(_conv(in_channels, channels[0]), _conv(channels[0], channels[0]))]
        for cin, cout in zip(channels[:-1], channels[1:]):
            levels.append(nn.Sequential(_conv(cin, cout, stride=2), _conv(cout, cout)))
        self.levels = nn.ModuleList(levels)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:
        feats = []
        for level in self.levels:
            x = level(x)
            feats.append(x)
        return feats


class Decoder(nn.Module):
    """U-Net decoder: from the bottleneck up, concatenating the skip feature of each level.

    forward(feats) with feats as returned by :class:`Encoder` -> (B, 3, H, W) unbounded RGB values.
    """

    def __init__(self, channels: tuple[int, ...]) -> None:
        super().__init__()
        ups, merges = [], []
        for level in range(len(channels) - 2, -1, -1):
            ups.append(_conv(channels[level + 1], channels[level]))
            merges.append(nn.Sequential(_conv(2 * channels[level], channels[level]),
                                        _conv(channels[level], channels[level])))
        self.ups = nn.ModuleList(ups)
        self.merges = nn.ModuleList(merges)
        self.head = nn.Conv2d(channels[0], 3, 3, padding=1)

    def forward(self, feats: list[torch.Tensor]) -> torch.Tensor:
        x = feats[-1]
        for i, (up, merge) in enumerate(zip(self.ups, self.merges)):
            skip = feats[-2 - i]
            x = up(F.interpolate(x, scale_factor=2.0, mode="nearest"))  # (B, c_l, H_l, W_l)
            x = merge(torch.cat([x, skip], dim=1))
        return self.head(x)


class FrameGenerator(nn.Module):
    """Reference frame + reference structure + target structure -> target frame.

    forward(ref_image (B, 3, H, W) in [0, 1], ref_structure (B, S, H, W), tgt_structure (B, S, H, W))
        -> (B, 3, H, W), about [0, 1] (not clamped, so the loss keeps its gradient; clamp for display).
    """

    def __init__(self, config: FrameGeneratorConfig) -> None:
        super().__init__()
        self.config = config
        self.image_encoder = Encoder(3, config.channels)
        self.pose_encoder = Encoder(config.structure_channels, config.channels)
        self.decoder = Decoder(config.channels)
        if config.output == "residual":  # start as copy-reference
            nn.init.zeros_(self.decoder.head.weight)
            nn.init.zeros_(self.decoder.head.bias)

    def forward(self, ref_image: torch.Tensor, ref_structure: torch.Tensor,
                tgt_structure: torch.Tensor) -> torch.Tensor:
        batch = ref_image.shape[0]
        img_feats = self.image_encoder(ref_image * 2.0 - 1.0)
        # One pass of the shared pose encoder over both structures: (2B, S, H, W).
        pose_feats = self.pose_encoder(torch.cat([ref_structure, tgt_structure], dim=0))
        feats = [f_img + f_pose[batch:] - f_pose[:batch] for f_img, f_pose in zip(img_feats, pose_feats)]
        out = self.decoder(feats)  # (B, 3, H, W)
        if self.config.output == "direct":
            return torch.sigmoid(out)
        return ref_image + out

    def encode_reference(self, ref_image: torch.Tensor, ref_structure: torch.Tensor) -> list[torch.Tensor]:
        """What the target frames share: ``enc_img(x_ref) - enc_pose(p_ref)`` per encoder level.

        Args:
            ref_image: (B, 3, H, W) in [0, 1]. ref_structure: (B, S, H, W).
        Returns:
            Per level (B, C_l, H_l, W_l) features; a reference used for many targets is encoded once.
        """
        img_feats = self.image_encoder(ref_image * 2.0 - 1.0)
        ref_feats = self.pose_encoder(ref_structure)
        return [fi - fp for fi, fp in zip(img_feats, ref_feats)]

    def decode(self, reference: list[torch.Tensor], ref_image: torch.Tensor,
               tgt_structure: torch.Tensor) -> torch.Tensor:
        """Target frames from :meth:`encode_reference`'s features: (B, 3, H, W), about [0, 1].

        ``reference`` and ``ref_image`` have batch B or 1 (one reference for every target).
        """
        tgt_feats = self.pose_encoder(tgt_structure)
        y = self.decoder([b + t for b, t in zip(reference, tgt_feats)])  # (B, 3, H, W)
        return torch.sigmoid(y) if self.config.output == "direct" else ref_image + y


class PatchDiscriminator(nn.Module):
    """A small conditional patch discriminator (pix2pix style, no normalisation).

    forward(image (B, 3, H, W) in [0, 1], structure (B, S, H, W)) -> (B, 1, H/8, W/8) logits.
    """

    def __init__(self, structure_channels: int, width: int = 32) -> None:
        super().__init__()
        self.net = nn.Sequential(
            _conv(3 + structure_channels, width, stride=2),
            _conv(width, 2 * width, stride=2),
            _conv(2 * width, 4 * width, stride=2),
            _conv(4 * width, 4 * width),
            nn.Conv2d(4 * width, 1, 3, padding=1),
        )

    def forward(self, image: torch.Tensor, structure: torch.Tensor) -> torch.Tensor:
        return self.net(torch.cat([image * 2.0 - 1.0, structure], dim=1))


def gaussian_window(size: int = 11, sigma: float = 1.5, *, dtype=torch.float32) -> torch.Tensor:
    """(size,) normalised 1D Gaussian window."""
    x = torch.arange(size, dtype=dtype) - (size - 1) / 2.0
    w = torch.exp(-(x**2) / (2.0 * sigma**2))
    return w / w.sum()


def ssim(x: torch.Tensor, y: torch.Tensor, *, data_range: float = 1.0, window: int = 11,
         sigma: float = 1.5) -> torch.Tensor:
    """Structural similarity (Wang et al. 2004) with a Gaussian window, per image.

    Args:
        x, y: (B, C, H, W) images with values in [0, data_range].
    Returns:
        (B,) mean SSIM over channels and valid (unpadded) window positions.
    """
    channels = x.shape[1]
    w1 = gaussian_window(window, sigma, dtype=x.dtype).to(x.device)
    kx = w1.view(1, 1, 1, window).expand(channels, 1, 1, window)  # (C, 1, 1, k)
    ky = w1.view(1, 1, window, 1).expand(channels, 1, window, 1)  # (C, 1, k, 1)

    def blur(t: torch.Tensor) -> torch.Tensor:
        t = F.conv2d(t, kx, groups=channels)
        return F.conv2d(t, ky, groups=channels)

    c1 = (0.01 * data_range) ** 2
    c2 = (0.03 * data_range) ** 2
    mu_x, mu_y = blur(x), blur(y)
    sxx = blur(x * x) - mu_x**2
    syy = blur(y * y) - mu_y**2
    sxy = blur(x * y) - mu_x * mu_y
    num = (2 * mu_x * mu_y + c1) * (2 * sxy + c2)
    den = (mu_x**2 + mu_y**2 + c1) * (sxx + syy + c2)
    return (num / den).mean(dim=(1, 2, 3))


@dataclass
class ReconstructionLoss:
    """``total`` to back-propagate; ``l1`` and ``ssim`` (the SSIM value, not the loss) as floats."""

    total: torch.Tensor
    l1: float
    ssim: float


def reconstruction_loss(pred: torch.Tensor, target: torch.Tensor, *, ssim_weight: float) -> ReconstructionLoss:
    """L1 + ssim_weight * (1 - SSIM) on (B, 3, H, W) images in [0, 1]."""
    l1 = (pred - target).abs().mean()
    s = ssim(pred, target).mean()
    total = l1 + ssim_weight * (1.0 - s)
    return ReconstructionLoss(total=total, l1=float(l1.detach()), ssim=float(s.detach()))


def count_parameters(module: nn.Module) -> int:
    return int(sum(p.numel() for p in module.parameters()))


def images_to_tensor(images: np.ndarray) -> torch.Tensor:
    """(B, H, W, 3) uint8 -> (B, 3, H, W) float32 in [0, 1]."""
    return torch.from_numpy(np.ascontiguousarray(images)).permute(0, 3, 1, 2).float().div_(255.0)


def tensor_to_images(t: torch.Tensor) -> np.ndarray:
    """(B, 3, H, W) float in [0, 1] -> (B, H, W, 3) uint8 (rounded)."""
    t = t.detach().clamp(0.0, 1.0).mul(255.0).round_().to(torch.uint8)
    return np.ascontiguousarray(t.permute(0, 2, 3, 1).cpu().numpy())


def generate(model: FrameGenerator, ref_images: np.ndarray, ref_structures: np.ndarray,
             tgt_structures: np.ndarray, *, batch_size: int = 8) -> np.ndarray:
    """Run the generator at inference (``torch.inference_mode``, channels_last).

    Args:
        model: a frame generator (put in eval mode here).
        ref_images: (B, H, W, 3) uint8 reference frames.
        ref_structures, tgt_structures: (B, S, H, W) float32 structure maps.
        batch_size: frames per forward pass.
    Returns:
        (B, H, W, 3) uint8 generated target frames.
    """
    size = model.config.image_size
    n = ref_images.shape[0]
    expected_s = (model.config.structure_channels, size, size)
    if ref_images.shape[1:] != (size, size, 3):
        raise ValueError(f"reference frames must be (B, {size}, {size}, 3), got {ref_images.shape}")
    for name, s in (("ref_structures", ref_structures), ("tgt_structures", tgt_structures)):
        if s.shape != (n, *expected_s):
            raise ValueError(f"{name} must be ({n}, {expected_s}), got {s.shape}")
    model.eval()
    model = model.to(memory_format=torch.channels_last)
    out = np.empty((n, size, size, 3), np.uint8)
    with torch.inference_mode():
        for start in range(0, n, batch_size):
            sl = slice(start, start + batch_size)
            x = images_to_tensor(ref_images[sl]).contiguous(memory_format=torch.channels_last)
            ps = torch.from_numpy(np.ascontiguousarray(ref_structures[sl], np.float32))
            pt = torch.from_numpy(np.ascontiguousarray(tgt_structures[sl], np.float32))
            base = model.encode_reference(x, ps.contiguous(memory_format=torch.channels_last))
            y = model.decode(base, x, pt.contiguous(memory_format=torch.channels_last))
            out[sl] = tensor_to_images(y)
    return out
