"""Real data and file formats: dataset loaders (``datasets``, ``middlebury`` for 2014 pairs,
``middlebury_rail`` for the seven-view 2005/2006 scenes, ``colmap``, ``tum``, ``formats``), the real scenes
shipped with the kit (``samples``), file reading and writing (``fileio``, ``file_writers``, ``textparse``)
and resampling (``resample``).

May import: core, world, classical.
"""
