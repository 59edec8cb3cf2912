"""The keypoint-conditioned frame generator (reference frame + structures -> target frame).

- :mod:`.model`: the network (feature analogy, U-Net decoder), SSIM, losses, inference (:func:`generate`).
- :mod:`.data`: synthetic appearance sequences and pairs, structures, splits, the npz cache.
- :mod:`.render_data`: rendering those sequences with the Anny body / face renderers from real captures.
- :mod:`.train`: the training loop with resumable checkpoints.
- :mod:`.checkpoint`: safetensors checkpoints (config in the metadata) and the resume state.
- :mod:`.baselines`: copy-reference and limb-warp.
- :mod:`.evaluate`: PSNR / SSIM on held-out pairs, JSON, contact sheets.
"""
