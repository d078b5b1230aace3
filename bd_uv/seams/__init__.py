"""Automatic seams: cut islands that cannot be certified as they are into certified disk charts."""
from .auto import unwrap_auto
from .charts import chart_maps
from .crossings import boundary_crossings
from .cut_graph import cut_graph
from .edges import edge_table
from .split import fiedler_split, fiedler_split_many

__all__ = ["unwrap_auto", "boundary_crossings", "chart_maps", "cut_graph", "edge_table",
           "fiedler_split", "fiedler_split_many"]
