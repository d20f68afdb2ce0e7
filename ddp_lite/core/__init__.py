"""The kit's data model and the checks everything shares: cameras (``camera``), views and scenes
(``views``), argument checks (``checks``), the base of a config's sections (``settings``), progress
bars (``progress``), output paths (``outpaths``), atomic writes and the regular-file check every reader
makes (``files``), others' names shown escaped (``printable``), arrays and a JSON structure in one ``.npz``
that loads without pickle (``array_archive``), lengths in pixels that scale with the image (``pixel_lengths``),
the folder of the fit and scene caches and the digest of the kit's source (``disk_cache``).

Imports no other part of ddp_lite.
"""
