"""Full-field DIC: displacement, shape and strain over a ROI (2D or stereo), its ROI and
grid, the stereo pairing, the uncertainty from the matching mismatch, CSV/plot output and
the import of VIC-3D / DICe results.

Implementation only: public names are re-exported from :mod:`jointwear.dic`.
"""
