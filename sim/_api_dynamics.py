"""Public names of the dynamics part of jointwear.sim (mechanism, contact, friction, integrator)."""

__all__: list[str] = []
