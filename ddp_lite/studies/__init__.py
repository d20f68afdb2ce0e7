"""The notebooks' studies, each a notebook's driver: the real Middlebury cases and their fills
(``real_cases``), the paper's Table 6 on its own scenes (``table6``, notebook 06), the real suite over every
Middlebury scene with ground truth (``real_suite``, the quality benchmark), the kit's additions put on the
paper's recipe one at a time (``additions``, notebook 10), DDP on multi-view stereo and Kinect-style depth
(``mvs_kinect_experiments``, notebook 12).

May import: core, world, classical, method, data, evaluation.
"""
