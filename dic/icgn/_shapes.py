"""The IC-GN's subset shape functions as a table: name -> :class:`ShapeFunction` record
(numba-free, read by the parameter checks, the kernels' options and the result files).

A record says which of the kernels' 12 warp parameters ``(u, du/dx, du/dy, d2u/dx2, d2u/dxdy,
d2u/dy2, v, dv/dx, ...)`` the shape solves, which result variables it writes, which numba
system and warp the kernels use for it (``second_order``, the kernels' ``opts[1]``), whether its
references can be preloaded (the affine fast path of tracking) and which outputs an incremental
sequence cannot carry across a reference update. ``CorrelationParams(shape=...)`` accepts every
name and alias of the table; :func:`register_shape` adds a row (a shape the kernels do not have
yet also needs its numba system and warp: one module, and a branch on its value in
:func:`jointwear.dic.icgn._solve.solve_point`; see docs/development.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from jointwear.errors import ParameterError

__all__ = ["ShapeFunction", "SHAPE_FUNCTIONS", "register_shape", "shape_function"]

#: an output variable: (name, position in the 12-vector, units, long name)
Output = tuple[str, int, str, str]

FIRST_ORDER_OUTPUTS: tuple[Output, ...] = (
    ("u", 0, "pixel", "displacement along x (image columns, right)"),
    ("du_dx", 1, "1", "displacement gradient du/dx"),
    ("du_dy", 2, "1", "displacement gradient du/dy"),
    ("v", 6, "pixel", "displacement along y (image rows, down)"),
    ("dv_dx", 7, "1", "displacement gradient dv/dx"),
    ("dv_dy", 8, "1", "displacement gradient dv/dy"),
)
SECOND_ORDER_OUTPUTS: tuple[Output, ...] = tuple(
    (f"d2{c}_{d}", first + k, "pixel-1", f"second derivative d2{c}/{d}")
    for c, first in (("u", 3), ("v", 9))
    for k, d in enumerate(("dx2", "dxdy", "dy2"))
)


@dataclass(frozen=True)
class ShapeFunction:
    """One subset shape function (a row of :data:`SHAPE_FUNCTIONS`).

    Parameters
    ----------
    name : str
        The name ``CorrelationParams(shape=...)`` and ``--shape`` take, and the result files
        state (``dic_shape_function``).
    description : str
        One line for messages and the help.
    parameters : tuple of int
        Positions of the solved parameters in the kernels' 12-vector.
    outputs : tuple of (str, int, str, str)
        Result variables: name, position in the 12-vector, units, long name.
    second_order : bool
        The kernels' branch (``opts[1]``): the 12-parameter second-order system and warp, or
        the affine one.
    preload : bool
        References can be kept in memory for tracking (the affine fast path).
    not_incremental : tuple of str
        Outputs an incremental sequence cannot carry across a reference update (NaN there).
    aliases : tuple of str
        Other names for it.
    """

    name: str
    description: str
    parameters: tuple[int, ...]
    outputs: tuple[Output, ...]
    second_order: bool = False
    preload: bool = False
    not_incremental: tuple[str, ...] = ()
    aliases: tuple[str, ...] = ()


#: the table: every name and alias -> its record
SHAPE_FUNCTIONS: dict[str, ShapeFunction] = {}


def register_shape(shape: ShapeFunction) -> ShapeFunction:
    """Add ``shape`` to :data:`SHAPE_FUNCTIONS` under its name and aliases; a name already
    taken by another record is refused."""
    for key in (shape.name, *shape.aliases):
        if SHAPE_FUNCTIONS.get(key, shape) != shape:
            raise ParameterError(f"shape function {key!r} is already registered")
    for key in (shape.name, *shape.aliases):
        SHAPE_FUNCTIONS[key] = shape
    return shape


def shape_function(name: str) -> ShapeFunction:
    """The record of the shape function called ``name``, or a ParameterError naming them."""
    try:
        return SHAPE_FUNCTIONS[name]
    except (KeyError, TypeError):
        known = ", ".join(
            f"{s.name!r} ({s.description})" for s in dict.fromkeys(SHAPE_FUNCTIONS.values())
        )
        raise ParameterError(f"shape={name!r}: expected one of {known}") from None


AFFINE = register_shape(
    ShapeFunction(
        name="affine",
        description="first order",
        parameters=(0, 1, 2, 6, 7, 8),
        outputs=FIRST_ORDER_OUTPUTS,
        preload=True,
        aliases=("first",),
    )
)
QUADRATIC = register_shape(
    ShapeFunction(
        name="quadratic",
        description="second order",
        parameters=tuple(range(12)),
        outputs=FIRST_ORDER_OUTPUTS + SECOND_ORDER_OUTPUTS,
        second_order=True,
        not_incremental=tuple(o[0] for o in SECOND_ORDER_OUTPUTS),
        aliases=("second",),
    )
)
