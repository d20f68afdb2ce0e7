"""The quality study's recipes besides the kit's own (``bench_quality.py --recipes NAME``): name → ``FitConfig``
overrides on top of a profile's ``kit`` config, each with the one line of why it was tried. What each one
measured: docs/studies/benchmark_history.md and docs/studies/quality_study.md; the kit's recipes: ``ddp_lite.method.kit.recipes``.
"""
from __future__ import annotations

# The recipes of earlier studies pin what they ran where `class` has changed since, or might (no colour
# image in the net's input: NO_IMAGE; colour edges on grey: GREY; at the edge-strength study's strength
# 100: E100; at 10: EDGE10; the noise input too: NOISE). The `ci-` recipes are `ci`'s own; those of the
# colour-image study pin its recipe then (strength 10, no flatness term: CI_E10).
NO_IMAGE = dict(image_input=0.0)
GREY = dict(edge_guide="grey", **NO_IMAGE)
E100 = dict(smoothness_edge=100.0)
EDGE10 = dict(smoothness_edge=10.0, **GREY)
NOISE = dict(net_input="noise", noise_channels=16, **EDGE10)
IMAGE = dict(image_input=1.0, image_blur=1.0)  # class's colour image in the input (the colour-image study)
CI_E10 = dict(smoothness_edge=10.0, flatness=0.0)  # ci until the `ci` catch-up: strength 10, no flatness term
STUDY = {
    "kit-ens2": dict(ensemble=2),  # real data first: the mean of two fits, ...
    "kit-ens3": dict(ensemble=3),  # ... of three,
    "patience100": dict(patience=100),  # ... a longer plateau before the rate cut and the stop,
    "e100": dict(smoothness_edge=100.0),  # ... colour edges at strength 100 (textured photos),
    "blur2": dict(image_blur=2.0),  # ... the colour image in the input blurred by 2 px,
    "fillin": dict(fill_input=1.0),  # ... a colorization fill of the input disparity as one more input channel,
    "affinity": dict(affinity=1.0, smoothness=0.0, flatness=0.0),  # ... the colorization energy as the hole term,
    "no-image": dict(**GREY, **E100),  # class before the colour-image study: no colour image in the net's input
    "image-e100": dict(**IMAGE, **E100),  # the colour-image study: the colour image in the input, at strength 100 ...
    "image-sharp": dict(image_input=1.0, image_blur=0.0, **E100),  # ... unblurred
    "image-blur2": dict(image_input=1.0, image_blur=2.0, **E100),  # ... blurred more
    "image0.3": dict(image_input=0.3, image_blur=1.0, **E100),  # ... at a third of the coordinates' scale
    "image-patience100": dict(patience=100, **IMAGE, **E100),  # ... with a longer plateau
    "image-dip1200": dict(auto_stop=False, iterations=1200, lr_milestones=(), **IMAGE, **E100),  # ... DIP's schedule
    "image-e1000": dict(smoothness_edge=1000.0, **IMAGE),  # the image at other strengths (the new class: 300)
    "ci-no-image": dict(**GREY, **CI_E10),  # ci before the colour-image study
    "ci-image-sharp": dict(image_input=1.0, image_blur=0.0, **CI_E10),  # ci with the colour image unblurred, ...
    "ci-image-blur1": dict(image_input=1.0, image_blur=1.0, **CI_E10),  # ... blurred by 1 px (ci keeps 0.5)
    "ci-e10": CI_E10,  # ci after the colour-image study (the colour image, σ 0.5 px); then, the `ci` catch-up:
    "ci-e3": dict(smoothness_edge=3.0, flatness=0.0),  # its colour-edge strength, without the flatness term
    "ci-e30": dict(smoothness_edge=30.0, flatness=0.0),
    "ci-e100": dict(smoothness_edge=100.0, flatness=0.0),
    "ci-e300": dict(smoothness_edge=300.0, flatness=0.0),
    "ci-e1000": dict(smoothness_edge=1000.0, flatness=0.0),
    "ci-e100-meshgrid": dict(smoothness_edge=100.0, flatness=0.0, net_input="meshgrid", noise_channels=2),
    "ci-e100-smooth2": dict(smoothness_edge=100.0, flatness=0.0, smoothness=2.0),
    "ci-flat0.3": dict(flatness=0.3),  # strength 100 with the flatness term at 0.3 (ci now: 0.6)
    "fp32": dict(bf16=False),  # class in float32 (it runs the net in bfloat16 where the CPU has it)
    "image-warp-w10": dict(gammas=(0.88, 0.02)),  # rgbd+warp with the warp term at 0.10 (class's recipe)
    "image-flat0.3": dict(flatness=0.3),  # class's recipe with the flatness term at 0.3, ...
    "image2": dict(image_input=2.0),  # ... the colour image at twice the coordinates' scale,
    "image-wide": dict(channels=(32, 64, 128, 256, 512)),  # ... the paper's widths,
    "image-smooth2": dict(smoothness=2.0),  # ... curvature weight 2
    "warp-patience100": dict(patience=100),  # ... a longer plateau (run with rgbd+warp)
    "lr5e-3": dict(lr=5e-3),  # the flatness-reach study, on class's recipe: Adam's rate halved, ...
    "lr2e-2": dict(lr=2e-2),  # ... doubled,
    "lz1": dict(lambda_z=1.0),  # ... L_disp all L1 (the paper: 0.8 L1 + 0.2 SSIM),
    "reach4": dict(flatness_reach=4.0),  # ... the flatness term only at the border and 4 px into enclosed holes,
    "rgb0.05": dict(gammas=(0.95, 0.05)),  # ... the colour term at 0.05 (the paper's rgbd: 0.01),
    "reach4-rgb0.05": dict(flatness_reach=4.0, gammas=(0.95, 0.05)),  # ... both,
    "margin1.1": dict(disparity_margin=1.1),  # ... the disparity range 1.1× around the valid depth's (default 1.25)
    "reach4-margin1.1": dict(flatness_reach=4.0, disparity_margin=1.1),  # the rgbd+warp study: the two together; then rgbd+warp's own:
    "warp0.05": dict(gammas=(0.93, 0.02)),  # ... the warp term at 0.05 (the paper's, and class's: 0.02), ...
    "warp0.07": dict(gammas=(0.91, 0.02)),  # ... 0.07,
    "warp-rgb0.05": dict(gammas=(0.93, 0.05)),  # ... the colour term at 0.05 beside the warp term's 0.02,
    "warp-lw0.85": dict(lambda_w=0.85),  # ... L_warp 85 % SSIM (Monodepth2's share; the paper: 50 %),
    "warp-flat1": dict(flatness=1.0),  # ... the flatness term at 1 (class: 0.6)
    "edge10": EDGE10,  # class before the edge-strength study
    "edge30": dict(smoothness_edge=30.0, **GREY),
    "e100-rgb": dict(edge_guide="rgb", **NO_IMAGE, **E100),  # colour edges measured on R, G, B (tried, not kept)
    "edge300": dict(smoothness_edge=300.0, **GREY),
    "edge1000": dict(smoothness_edge=1000.0, **GREY),
    "warp-w10": dict(gammas=(0.88, 0.02), **EDGE10),  # rgbd+warp with the warp term at 0.10 instead of 0.02
    "warp-w25": dict(gammas=(0.73, 0.02), **EDGE10),  # ... at 0.25
    "e100-flat0.3": dict(flatness=0.3, **GREY, **E100),  # edge 100 on grey with other hole-term weights
    "e100-flat1": dict(flatness=1.0, **GREY, **E100),
    "e100-smooth0.5": dict(smoothness=0.5, **GREY, **E100),
    "e100-smooth2": dict(smoothness=2.0, **GREY, **E100),
    "paper-losses": dict(smoothness=0.0, flatness=0.0, bf16=False, channels=(32, 64, 128, 256, 512), **NOISE),  # class before the quality study
    "paper-net": dict(channels=(32, 64, 128, 256, 512), flatness=0.0, **NOISE),  # class before the width study (one 32-512 fit)
    "curvature-ens3": dict(flatness=0.0, ensemble=3, **NOISE),  # class before the flatness study: the mean of three, no flatness
    "one-fit-curvature": dict(flatness=0.0, **NOISE),  # one fit of that recipe
    "flat0.3": dict(flatness=0.3, **NOISE),  # the flatness study: the flatness term at 0.3 instead of 0.6
    "flat1": dict(flatness=1.0, **NOISE),  # ... at 1
    "ens3": dict(ensemble=3, **NOISE),  # the mean of three fits of the flatness study's class recipe
    "noise-input": NOISE,  # class before the input study: the paper's noise input
    "meshgrid+noise": dict(net_input="meshgrid", noise_channels=16, **EDGE10),  # the coordinates and 14 noise channels
    "quarter-ens4": dict(channels=(8, 16, 32, 64, 128), ensemble=4, flatness=0.0, **NOISE),  # chosen on 8 cases, failed on the others
    "ema": dict(average_outputs=0.9),
    "cosine": dict(schedule="cosine"),
    "lr3e-3": dict(lr=3e-3),
    "lr3e-2": dict(lr=3e-2),
    "it300": dict(iterations=300),
    "pool": dict(down="pool"),
    "nearest": dict(up="nearest"),
    "zeros": dict(pad="zeros"),
    "jitter": dict(reg_noise_std=1 / 30),
    "margin1": dict(disparity_margin=1.0),
    "margin2": dict(disparity_margin=2.0),
    "l1only": dict(lambda_z=1.0),
    "rgb10": dict(gammas=(0.9, 0.1)),
    "autostop": dict(auto_stop=True, patience=50, plateau_decays=1, iterations=600, lr_milestones=()),
    "constant": dict(lr_milestones=()),
    "smooth0.1": dict(smoothness=0.1),
    "smooth1": dict(smoothness=1.0),
    "smooth10": dict(smoothness=10.0),
    "smooth3": dict(smoothness=3.0),
    "smooth0.3": dict(smoothness=0.3),
    "smooth1-edge0": dict(smoothness=1.0, smoothness_edge=0.0),
    "smooth1-edge30": dict(smoothness=1.0, smoothness_edge=30.0),
    "smooth1-it300": dict(smoothness=1.0, iterations=300),
    "smooth1-lr3e-3": dict(smoothness=1.0, lr=3e-3),
    "smooth1-ens3": dict(smoothness=1.0, ensemble=3),
    "holdout-blobs": dict(held_out_shape="blobs"),
    "step3": dict(step_reach=3.0),  # real data: the hole terms off within 3 px of a depth step of the input,
    "step6": dict(step_reach=6.0),  # ... within 6 px (occlusion bands are 2-10 px wide at 125×185)
    "blend-ring": dict(blend_paper=True, blend_weight=None),  # the photo recipe's blend, its weight from a held-out ring
    "occl": dict(warp_occlusion=True),  # the warp term skips the pixels the neighbour cannot see (method.kit.visibility)
    "fill-chosen": dict(blend_fill=None),  # the fill's share (0-0.5) chosen on held-out blobs of the valid depth
}
# every recipe above ran before `class` mixed a share of the colorization fill into its result
STUDY = {name: {"blend_fill": 0.0, **overrides} for name, overrides in STUDY.items()}
# the recipes below ran after `class` took its share of the fill, and keep it
STUDY.update({
    "narrow": dict(channels=(8, 16, 32, 64, 128)),  # time to quality: class's net at half its widths (2.1× less time per iteration held to AVX2)
    "mid": dict(channels=(12, 24, 48, 96, 192)),  # ... at three quarters of its widths: the narrow net lost on the blob holes
    # where the warp term costs on the real pair: turning it on also moves γ1, γ2 (0.98, 0.01 → 0.96, 0.02) ...
    "warp-g98": dict(gammas=(0.98, 0.01)),  # ... rgbd+warp at rgbd's γ: the warp term at 0.01
    "g96": dict(gammas=(0.96, 0.02)),  # ... rgbd at rgbd+warp's γ (run with rgbd: the warp share is dropped)
    "warp-holes3": dict(warp_reach=3.0),  # the warp term only in the holes and 3 px around them, not on the valid input
    "warp-holes3-conf": dict(warp_reach=3.0, warp_confidence=True),  # ... and there only where the images single out one depth
    # other photometric costs for the warp term, and a per-pixel weight on it (method.kit.warp_cost) ...
    "warp-census": dict(warp_cost="census"),  # ... a soft census of 7×7 patches in place of L1 + SSIM on intensities,
    "warp-gradient": dict(warp_cost="gradient"),  # ... L1 on the images' differences beside SSIM,
    "warp-texture": dict(warp_texture=True),  # ... the paper's cost, each pixel weighted by the image's change along its epipolar line
    "warp-census-conf": dict(warp_cost="census", warp_confidence=True),  # ... the census, only where the images single out one depth
    # ... the census at the paper's cost's size: the census's mean per pixel at the true depth on the real pair's valid
    # input is 1/0.59 of L1 + SSIM's (study_warp_costs.py --scale), so its share 0.02 × 0.59 (γ1 takes the rest)
    "warp-census-matched": dict(warp_cost="census", gammas=(0.9682, 0.02)),
    "warp-census-intensity": dict(warp_cost="census+intensity"),  # ... half L1 + SSIM, half the census at its size (×0.59)
    # whether the warp term's cost on the SGBM and occlusion holes is the auto-stop ending elsewhere: both variants
    # on one fixed schedule, the last iterate kept (class's cap of 600, its lr cut ×0.3 at 300 instead of a plateau's)
    "fixed600": dict(auto_stop=False, iterations=600, lr_milestones=(300,)),
    "fixed600-census": dict(warp_cost="census", auto_stop=False, iterations=600, lr_milestones=(300,)),  # ... the census on it
    # time to quality by fewer iterations (the real pair's fits run to ~575 of 600, the rendered scenes' to ~480):
    "cap300-p30": dict(iterations=300, patience=30),  # ... half the cap, both held-out plateaus 30 iterations instead of 50, same rate
    "cap250-lr2e-2": dict(iterations=250, lr=2e-2, patience=30, lr_milestones=(200,)),  # ... twice the rate to form the fill sooner, a fixed ×0.3 cut at 200 so a capped fit settles
    "cap300-cut240": dict(iterations=300, lr_milestones=(240,)),  # ... half the cap at class's patience 50 (patience 30 stopped blob fits early), a fixed ×0.3 cut at 240
})
