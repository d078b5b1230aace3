"""What ``build.py`` builds: the repo's paths, the bundled packages and the one Blender ships, the
Pythons and their Blender versions, the platforms and their wheel tags, what a zip may hold, and
the error every check raises."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = ROOT / "blender_manifest.toml"
REQUIREMENTS = ROOT / "requirements.txt"

# Packages the zips carry as wheels: the core's runtime needs and their own runtime dependencies
# (clarabel declares cffi, cffi needs pycparser). Versions come from requirements.txt.
BUNDLED = ("scipy", "clarabel", "cffi", "pycparser", "trimesh", "shapely", "qdldl", "spyrrow")
# Provided by Blender itself: never bundled, and no file of it may appear in a zip.
PROVIDED_BY_BLENDER = ("numpy",)
README = ROOT / "README.md"
# The table of the Blender versions we claim, their Python and the numpy they ship, in README.md:
# "| Blender | Python | numpy |" rows such as "| 5.2 LTS | 3.13 | 2.5.5 |".
BLENDER_ROW = re.compile(r"^\|\s*(\d+\.\d+[^|]*?)\s*\|\s*(3\.\d+)\s*\|\s*([\d., ]+?)\s*\|\s*$",
                        re.MULTILINE)


def blender_numpy(readme: Path = README) -> dict[str, tuple[str, ...]]:
    """``{python: numpy versions}`` of every Blender version README.md's table lists: a bundled
    wheel's numpy requirement must accept every one of them (a scipy whose range stops below
    Blender's numpy warns "A NumPy version >=... and <... is required", and breaks on the next)."""
    out: dict[str, list[str]] = {}
    for _, python, numpys in BLENDER_ROW.findall(readme.read_text(encoding="utf-8")):
        out.setdefault(python, []).extend(v.strip() for v in numpys.split(",") if v.strip())
    return {p: tuple(dict.fromkeys(v)) for p, v in out.items()}


BLENDER_NUMPY = blender_numpy()

PYTHONS = ("3.11", "3.13")
# Blender versions per Python: (blender_version_min, blender_version_max or None), and the zip name.
BLENDER_RANGE = {"3.11": ("4.2.0", "5.1.0"), "3.13": ("5.1.0", None)}
ZIP_NAME = {"3.11": "{id}-{version}-{platform}.zip", "3.13": "{id}-{version}-py313-{platform}.zip"}
# pip --platform tags per Blender platform. Blender itself ignores the glibc / macOS version in a
# tag; scipy 1.15.3 (cp311) needs macOS 12 on both Mac platforms.
PLATFORM_TAGS = {
    "linux-x64": ("manylinux_2_28_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64"),
    "windows-x64": ("win_amd64",),
    "macos-arm64": ("macosx_12_0_arm64",),
    "macos-x64": ("macosx_12_0_x86_64",),
}
# Environment markers of each platform, for evaluating a wheel's Requires-Dist.
PLATFORM_MARKERS = {
    "linux-x64": {"sys_platform": "linux", "platform_system": "Linux",
                  "platform_machine": "x86_64", "os_name": "posix"},
    "windows-x64": {"sys_platform": "win32", "platform_system": "Windows",
                    "platform_machine": "AMD64", "os_name": "nt"},
    "macos-arm64": {"sys_platform": "darwin", "platform_system": "Darwin",
                    "platform_machine": "arm64", "os_name": "posix"},
    "macos-x64": {"sys_platform": "darwin", "platform_system": "Darwin",
                  "platform_machine": "x86_64", "os_name": "posix"},
}
# What the zip may hold at its top level: the add-on and nothing else.
ZIP_TOP_LEVEL = {"__init__.py", "blender_manifest.toml", "README.md", "LICENSE",
                 "bd_uv", "operators", "ui", "scripts", "wheels"}
MAX_MB = 90.0



class BuildError(Exception):
    """A check failed; the message says which and what to do."""
