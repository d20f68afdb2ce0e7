"""Synthetic worlds: the scene catalogue (``scenes``, ``organic``), primitives and the ray-caster
(``render``, ``solids``, ``terrain``), textures (``textures``, ``photo_texture``) and neighbour
selection (``neighbors``), scenes rendered once and read back (``scene_cache``).

May import: core.
"""
