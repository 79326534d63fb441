"""The 2D subset-DIC engine over the IC-GN kernels: :class:`SubsetCorrelator` and its
parameters, integer-pixel seeds, image sequences, the result Dataset and its quick-look figure.

Implementation only: public names are re-exported from :mod:`jointwear.dic`.
"""
