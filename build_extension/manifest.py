"""``blender_manifest.toml`` rewritten for a zip: its wheel list, its platforms, the Blender
versions that run the zip's Python."""
from __future__ import annotations

import re
import tomllib

from .config import BLENDER_RANGE, BuildError

WHEELS_BLOCK = re.compile(r"^wheels = \[.*?^\]\n", re.MULTILINE | re.DOTALL)
PLATFORMS_LINE = re.compile(r"^platforms = \[.*?\]\n", re.MULTILINE | re.DOTALL)


def toml_list(key: str, items: list[str]) -> str:
    body = "".join(f'  "{item}",\n' for item in items)
    return f"{key} = [\n{body}]\n"


def with_wheels(manifest_text: str, wheel_names: list[str]) -> str:
    """``manifest_text`` with its ``wheels = [...]`` block listing ``./wheels/<name>``."""
    block = toml_list("wheels", [f"./wheels/{n}" for n in sorted(set(wheel_names))])
    if not WHEELS_BLOCK.search(manifest_text):
        raise BuildError("blender_manifest.toml has no `wheels = [` ... `]` block to fill")
    return WHEELS_BLOCK.sub(lambda _: block, manifest_text, count=1)


def with_platforms(manifest_text: str, platforms: list[str]) -> str:
    line = "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]\n"
    return PLATFORMS_LINE.sub(lambda _: line, manifest_text, count=1)


def with_blender_range(manifest_text: str, python: str) -> str:
    """``manifest_text`` restricted to the Blender versions that run ``python``."""
    low, high = BLENDER_RANGE[python]
    line = f'blender_version_min = "{low}"\n'
    if high is not None:
        line += f'blender_version_max = "{high}"\n'
    text, n = re.subn(r'^blender_version_min = .*\n(blender_version_max = .*\n)?', line,
                      manifest_text, count=1, flags=re.MULTILINE)
    if n != 1:
        raise BuildError("blender_manifest.toml has no blender_version_min line")
    return text


def manifest_data(text: str) -> dict:
    return tomllib.loads(text)
