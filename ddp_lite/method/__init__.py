"""Deep Depth Prior itself. The paper's loss in one screen (``paper_method``) and its parts
(``disparity``, ``losses``, ``warp``, ``nets``, ``variants``); one fit (``fit``, ``fit_inputs``,
``loop``, ``config``, ``device``); the kit's additions beside it (``hole_losses``, ``hole_terms``, ``visibility``, ``warp_confidence``, ``warp_cost``,
``coarse_to_fine``) and its combinations of fits, with ``complete_depth``, the entry point
(``combine``, over ``blend`` and ``ensemble``); independent fits side by side (``side_by_side``); a working-size fit sharpened at a photo's own resolution (``full_resolution``); Deep Image Prior (``dip``); size and method switches
(``profiles``, ``recipes``) and the loss a config optimises, written out (``equation``); the fit
cache (``cache``, ``cache_entry``).

May import: core, classical.
"""
