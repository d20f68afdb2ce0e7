"""Where and how a fit runs, not what it computes: the device and bfloat16 (``device``), the memory
guard (``memory``), the fit cache (``cache``: its key names the profile, the recipe and the config, from
``method/``) and one cache entry's file format (``cache_entry``), NumPy arrays into torch's layout
(``tensors``).

May import: core, paper, kit, method.
"""
