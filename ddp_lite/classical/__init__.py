"""Classical depth, the kit's foil and input: the stereo matcher (``stereo``), hole and sensor models
(``holes``, ``kinect``) and the classical fills DDP is compared with: ``baselines`` names them all,
``depth_fills`` holds those that see the depth alone, ``guided_fills`` those guided by the colour image,
and the image-guided edge-aware solve that sharpens any fill toward the colour edges (``full_resolution``).

May import: core.
"""
