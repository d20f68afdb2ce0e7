"""Where and how a fit runs, not what it computes: the run's options (``options``: ``RunOptions``, passed
to every entry point that runs a fit), the device and bfloat16 (``device``; the net's precision changes
the numbers, so it is a section of the method's ``FitConfig``, defined there), NumPy arrays into torch's
layout (``tensors``), the memory guard (``memory``), independent fits side by side in threads
(``side_by_side``), and the file format of one entry of the fit cache (``cache_entry``; the cache itself,
whose key names the profile, the recipe, the config and the run's options, is ``method/fit_cache``).

May import: core, paper.
"""
