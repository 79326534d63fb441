"""Public names of full-field DIC (``jointwear.dic``): :func:`measure_field` (2D or stereo
displacement, shape and strain over a ROI), :class:`FieldParams`, :func:`write_field_csv`
(VIC-3D-like CSV export), :func:`plot_field` (contour maps over the surface) and
:func:`read_field` (VIC-3D CSV / DICe results imported for comparison)."""

from jointwear.dic.field._import import read_field
from jointwear.dic.field._io import plot_field, write_field_csv
from jointwear.dic.field._measure import FieldParams, measure_field

__all__ = ["FieldParams", "measure_field", "write_field_csv", "plot_field", "read_field"]
