"""What the kit adds to the paper, each named and off in the ``paper`` recipe: terms in the holes
(``hole_losses``, ``hole_terms``), the warp term's occlusion test (``visibility``), its confidence
mask (``warp_confidence``), its other costs and texture weights (``warp_cost``), all of them built
into one warp term the paper's loss takes as an argument (``warp_terms``), extra net inputs (the
colour image, a classical fill: ``net_inputs``), blends with a fill or the paper recipe's fit
(``blend``: their weights, shares and held-out pixels), ensembles (``ensemble``), the combinations of
whole fits built from them (``combine``) and the method switch (``recipes``). Each addition's settings
are a section of the fit's config defined beside its code, checked there and described there (its
part of a recipe's one-line description, ``describe()``, and of the equation, ``equation()``): ``HoleConfig``
(``hole_terms``), ``WarpConfig`` (``warp_terms``), ``NetInputConfig`` (``net_inputs``),
``CombinationConfig`` (``blend``, an ensemble's size included).

Blends and ensembles combine whole fits: a blend holds out valid pixels as the fit's auto-stop does
(``method/stopping.held_out_mask``), and each combination is a ``method/result.DepthResult`` (those two
the only files of ``method/`` itself the kit uses, both below it); ``method/complete`` runs the fits side
by side (``runtime/side_by_side``) and combines them with what is here.

May import: core, classical, paper, runtime, method.
"""
