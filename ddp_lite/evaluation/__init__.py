"""Judging completions: metrics (``metrics``), the synthetic cases and the notebooks' tables of the paper's
experiments (``experiments``), multi-view fusion (``fusion``), the plane sweep (``plane_sweep``) and
figures (``viz``). The notebooks' studies built on them are ``ddp_lite.studies``.

May import: core, world, classical, method, data.
"""
