"""Real data and file formats: dataset loaders (``datasets``, ``middlebury`` for 2014 pairs,
``middlebury_rail`` for the seven-view 2005/2006 scenes, ``colmap``, ``tum``, ``formats``), the real scenes
shipped with the kit (``samples``), the data root and the scenes installed in it (``installed``: the one
place every reader asks), a scene as a completion's input (``scene_input``), file reading and writing (``fileio``, ``file_writers``, ``textparse``)
and resampling (``resample``).

May import: core, world, classical.
"""
