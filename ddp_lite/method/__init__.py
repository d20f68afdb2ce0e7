"""Deep Depth Prior itself, in three rooms and the fit above them; each imports only those below it.

- ``paper/``: the paper's method and nothing else (the disparity transform, losses, warp, nets,
  variants and L_total, ``total_loss``, and the paper's settings, ``config``); it imports nothing
  of the rest.
- ``runtime/``: where and how a fit runs, not what it computes: its options, device, tensors, the
  memory guard, fits side by side in threads, the cache entry's file format. It imports only the
  paper (its nets' sizes, for the memory estimate).
- ``kit/``: what the kit adds, each addition named: hole terms, the warp term's masks and costs,
  extra net inputs, blends, ensembles, the method switch (recipes). It reaches the paper's loss as
  arguments (a warp term, occlusion tests, extra terms), never by the paper importing it.
- here, the fit: ground-truth-free stopping (``stopping``) and what a fit returns (``result``), the
  two files here the kit uses, the time a fit still needs (``time_left``), DIP's per-iteration tricks
  (``dip_tricks``), its config and profiles (``config``, which holds each room's settings as a section,
  ``profiles``), its inputs
  checked (``input_checks``), a setting that acts on nothing said before the fit (``inert_settings``), a
  keyword given to the wrong place named with where it goes (``misplaced_arguments``), the loop (``loop``) and
  its optimiser (``adam``),
  one fit (``fit``, which composes the paper's loss with the kit's terms), fits done once (``fit_cache``),
  the entry point ``complete_depth``, the pipeline that runs the fits and the kit's combinations of them
  (``complete``), coarse-to-fine (``coarse_to_fine``), Deep Image Prior (``dip``) and the loss a config
  optimises, written out (``equation``).

May import: core, classical.
"""
