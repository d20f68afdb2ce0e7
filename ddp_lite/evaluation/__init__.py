"""Judging completions: metrics (``metrics``), experiments and real cases (``experiments``,
``mvs_kinect_experiments``, ``real_cases``, the kit's additions one at a time: ``additions``), multi-view fusion (``fusion``), the plane sweep
(``plane_sweep``) and figures (``viz``).

May import: core, world, classical, method, data.
"""
