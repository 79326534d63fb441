"""Public names of the wear part of jointwear.sim (Archard wear, cycle updates, wear maps)."""

__all__: list[str] = []
