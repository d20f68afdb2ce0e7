"""Judging completions: metrics (``metrics``), the synthetic cases and the notebooks' tables of the paper's
experiments (``experiments``), where one method stands among others, as a sentence (``standing``),
multi-view fusion (``fusion``; Open3D as it imports it, ``open3d_loader``), the plane sweep (``plane_sweep``)
and figures (``viz``). The notebooks' studies built on them are ``ddp_lite.studies``.

May import: core, world, classical, method, data.
"""
