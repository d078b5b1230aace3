"""The atlas: charts packed by their true outlines (spyrrow), and the layout certificate."""
from .atlas import Packed, pack_islands
from .layout_certificate import LayoutCertificate, layout_certificate, least_gaps
from .options import GROUPINGS, ROTATIONS, PackOptions, udim_tile
from .uv_islands import uv_islands
