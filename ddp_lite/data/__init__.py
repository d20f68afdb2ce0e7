"""Real data and file formats: dataset loaders (``datasets``, ``middlebury``, ``colmap``, ``tum``,
``formats``), file reading and writing (``fileio``, ``file_writers``, ``textparse``) and resampling (``resample``).

May import: core, world, classical.
"""
