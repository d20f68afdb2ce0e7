"""Deep Depth Prior itself, in three rooms and the fit between them.

- ``paper/``: the paper's method and nothing else (the disparity transform, losses, warp, nets,
  variants and L_total, ``total_loss``); it imports nothing of the kit.
- ``kit/``: what the kit adds, each addition named: hole terms, the warp term's masks and costs,
  extra net inputs, blends, ensembles, the method switch (recipes). It reaches the paper's loss as
  arguments (a warp term, occlusion tests, extra terms), never by the paper importing it.
- ``runtime/``: where and how a fit runs: device, tensors, the memory guard, the fit cache.
- here, the fit: its config and profiles (``config``, ``profiles``), its inputs (``fit_inputs``),
  ground-truth-free stopping (``stopping``) and the time a fit still needs (``time_left``), the
  loop (``loop``), one fit (``fit``, which composes the paper's loss with the kit's terms), the entry
  point ``complete_depth`` over the kit's combinations (``combine``), independent fits side by side
  (``side_by_side``), coarse-to-fine (``coarse_to_fine``), a working-size fit sharpened at a photo's
  own resolution (``full_resolution``), Deep Image Prior (``dip``) and the loss a config optimises,
  written out (``equation``).

May import: core, classical.
"""
