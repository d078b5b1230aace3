"""The choices ``uv.bd_unwrap`` offers (``unwrap.UV_OT_bd_unwrap``'s enum properties): method,
seams, overlaps, boundary and frames, each with the words shown in its menu and tooltip."""

_METHODS = (
    ('lscm', "BD-LSCM", "Conformal energy (Lipman 2012, section 5): closest to Blender's "
     "Conformal, with a certified distortion bound"),
    ('arap', "BD-ARAP", "As-rigid-as-possible energy: keeps areas and lengths too, within the "
     "same certified bound"),
    ('dirichlet', "BD-Dirichlet", "Dirichlet (harmonic) energy within the bound: smooth, meant "
     "for a fixed boundary (Circle, Rectangle, Pinned Polygon)"),
    ('biharmonic', "BD-Biharmonic", "Biharmonic energy (Lipman 2012, eq. 6.1): smoother than "
     "Dirichlet, meant for a fixed boundary"),
    ('stretch-l1', "BD-L1 Stretch", "Sum of each face's singular values by area (section 6.1): "
     "evens out texel density within the bound"),
)
_SEAMS = (
    ('NEEDED', "Add Where Needed", "Keep the marked seams; add seams (marked on the mesh) only "
     "to islands that cannot be certified within C as they are (closed meshes, handles), their "
     "charts within C 2 and Limit Stretch; non-manifold vertices and edges and flipped parts "
     "are split. With Minimise, From Current UVs, a fixed Boundary or pinned UVs: as Marked"),
    ('MARKED', "Marked", "Cut along the marked seams only: every island must be a disk"),
    ('AUTO', "Search All Islands", "Keep the marked seams and search seams on every island, "
     "also those already certifiable, until every chart is within C and Limit Stretch; the "
     "added seams are marked on the mesh"),
)
_OVERLAP = (
    ('CUT', "Cut Into Pieces", "An island whose UVs would lie over themselves is cut into "
     "overlap-free pieces (no UV moves within a piece); the cut edges are marked as seams"),
    ('KEEP', "Keep as One Island", "An island whose UVs would lie over themselves is not written: "
     "it keeps its UVs and the report names it (mark seams, or let bd-uv cut it)"),
)
_BOUNDARY = (
    ('free', "Free", "The boundary goes where the map puts it"),
    ('circle', "Circle", "The outer boundary onto a circle (holes stay free): a bijection, "
     "Lipman 2012, Theorems 5.1-5.2"),
    ('rectangle', "Rectangle", "The outer boundary onto a rectangle, corners at the four boundary "
     "vertices that best fit one, or at four pinned UVs (straighten a strip for a trim sheet)"),
    ('pinned', "Pinned Polygon", "The outer boundary onto the polygon its pinned UVs make"),
)
_FRAMES = (
    ('auto', "Auto", "Start from the conformal map (or a flip-free one) chosen by bd-uv"),
    ('input-uv', "From Current UVs", "Start from the UVs the faces have now: an island within C "
     "keeps its layout (scaled to its 3D area), one beyond C is bent only as far as C demands "
     "(frames from its UVs, Lipman 2012 eq. 4.21)"),
)
