"""Classical depth, the kit's foil and input: the stereo matcher (``stereo``), hole and sensor models
(``holes``, ``kinect``) and the classical fills DDP is compared with (``baselines``).

May import: core.
"""
