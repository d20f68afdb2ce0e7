"""Where and how a fit runs, not what it computes: its settings (``options``), the device and
bfloat16 (``device``), NumPy arrays into torch's layout (``tensors``), the memory guard (``memory``),
independent fits side by side in threads (``side_by_side``), and the file format of one entry of the
fit cache (``cache_entry``; the cache itself, whose key names the profile, the recipe and the config,
is ``method/fit_cache``).

May import: core, paper.
"""
