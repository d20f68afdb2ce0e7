"""The paper's method and nothing else: the depth↔disparity transform (``disparity``), SSIM and the
three losses (``losses``), the differentiable inverse warp (``warp``), the generators and their fixed
input (``nets``), the three variants and their γ (``variants``), L_total in one screen
(``total_loss``), and the paper's settings of a fit (``config``). The kit's additions enter only as arguments (extra terms, a warp term, an occlusion
test, extra input channels); nothing here imports them.

May import: core.
"""
