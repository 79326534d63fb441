"""Sample data and generators with ground truth (``jointwear.datasets``).

Generators are public submodules: ``jointwear.datasets.speckle`` (speckle images),
``jointwear.datasets.instruments`` (roundness-instrument files), ``jointwear.datasets.rig``
(virtual stereo rig footage).
"""
