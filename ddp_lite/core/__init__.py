"""The kit's data model and the checks everything shares: cameras (``camera``), views and scenes
(``views``), argument checks (``checks``), progress bars (``progress``), output paths (``outpaths``).

Imports no other part of ddp_lite.
"""
