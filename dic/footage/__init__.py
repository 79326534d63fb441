"""Footage tracking: rig videos and image sequences, body regions (TOML), SIFT
correspondence, frame-to-frame subset tracking, rigid-body fits, the motion Dataset and its
figure.

Implementation only: public names are re-exported from :mod:`jointwear.dic`.
"""
