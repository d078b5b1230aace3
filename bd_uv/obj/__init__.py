"""OBJ files: read by position index (``read``), written back with new UVs as their own text
(``patch``); both walk the records as ``text`` splits them."""
from .patch import patched_obj, polygon_corner_vt
from .read import read_obj

__all__ = ["patched_obj", "polygon_corner_vt", "read_obj"]
