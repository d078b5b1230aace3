"""A zip's contents: the extension staged for Blender's builder (the repo minus the manifest's
build exclusions, one platform's and Python's wheels), and the checks of the zip it built."""
from __future__ import annotations

import shutil
import tomllib
import zipfile
from pathlib import Path

from .blender_tools import blender_ext
from .config import BLENDER_RANGE, PROVIDED_BY_BLENDER, ROOT, ZIP_TOP_LEVEL
from .manifest import manifest_data
from .wheels import Wheel, normalize


def stage(stage_dir: Path, manifest_text: str, wheels: list[Wheel], skip: tuple[Path, ...]) -> None:
    """Copy the extension into ``stage_dir``: repo files minus the manifest's build exclusions
    (matched by Blender's own pattern code) and minus the directories in ``skip`` (output, cache),
    this platform's wheels, and ``manifest_text``."""
    patterns = manifest_data(manifest_text).get("build", {}).get("paths_exclude_pattern", [])
    matcher = blender_ext().PathPatternMatch(patterns)
    if stage_dir.exists():
        shutil.rmtree(stage_dir)
    stage_dir.mkdir(parents=True)

    def copy_tree(src: Path, rel: str) -> None:
        for entry in sorted(src.iterdir()):
            entry_rel = f"{rel}{entry.name}"
            if entry.is_dir():
                if entry.resolve() in skip:
                    continue
                if not matcher.test_path(entry_rel + "/"):
                    copy_tree(entry, entry_rel + "/")
            elif entry.is_file() and not matcher.test_path(entry_rel):
                if entry_rel == "blender_manifest.toml":
                    continue
                dst = stage_dir / entry_rel
                dst.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(entry, dst)

    copy_tree(ROOT, "")
    (stage_dir / "blender_manifest.toml").write_text(manifest_text)
    (stage_dir / "wheels").mkdir(exist_ok=True)
    for wheel in wheels:
        shutil.copy2(wheel.path, stage_dir / "wheels" / wheel.path.name)


def check_zip(zip_path: Path, platform: str, python: str, pins: dict[str, str],
              max_mb: float) -> list[str]:
    """Problems with a zip built for ``platform`` and ``python`` (empty when it is good)."""
    problems = []
    with zipfile.ZipFile(zip_path) as zf:
        names = zf.namelist()
        manifest = tomllib.loads(zf.read("blender_manifest.toml").decode())
    generated = manifest.get("build", {}).get("generated", {})
    if generated.get("platforms") != [platform]:
        problems.append(f"manifest [build.generated] platforms is {generated.get('platforms')}")
    low, high = BLENDER_RANGE[python]
    if (manifest.get("blender_version_min"), manifest.get("blender_version_max")) != (low, high):
        problems.append(f"manifest Blender range is {manifest.get('blender_version_min')} to "
                        f"{manifest.get('blender_version_max')}, not {low} to {high}")
    top = {n.split("/", 1)[0] for n in names}
    if top - ZIP_TOP_LEVEL:
        problems.append(f"unexpected top-level entries {sorted(top - ZIP_TOP_LEVEL)}: "
                        f"exclude them in [build] paths_exclude_pattern")
    if "__init__.py" not in names or "bd_uv/__init__.py" not in names:
        problems.append("the add-on's __init__.py or the bd_uv core is missing")
    zipped = {n.split("/", 1)[1] for n in names if n.startswith("wheels/") and n != "wheels/"}
    listed = {w.rsplit("/", 1)[1] for w in manifest.get("wheels", [])}
    if zipped != listed:
        problems.append(f"wheels in zip {sorted(zipped)} differ from manifest {sorted(listed)}")
    wheels = [Wheel(Path(n)) for n in sorted(zipped)]
    for wheel in wheels:
        if platform not in wheel.platforms():
            problems.append(f"{wheel.path.name} is for another platform")
        if not wheel.serves_python(python):
            problems.append(f"{wheel.path.name} is for another Python")
    for name, version in pins.items():
        if not any(w.name == name and w.version == version for w in wheels):
            problems.append(f"no {name} {version} wheel for {platform} / Python {python}")
    # No numpy: no numpy wheel, no numpy directory, no numpy packed inside a wheel.
    blocked = {normalize(n) for n in PROVIDED_BY_BLENDER}
    for name in names:
        parts = name.split("/")
        if blocked & {normalize(p) for p in parts[:-1]} or (
                name.startswith("wheels/") and normalize(parts[-1].split("-")[0]) in blocked):
            problems.append(f"{name}: numpy must never be bundled")
    if wheels and not problems:
        with zipfile.ZipFile(zip_path) as zf:
            for wheel in wheels:
                with zf.open(f"wheels/{wheel.path.name}") as fh, zipfile.ZipFile(fh) as inner:
                    if blocked & {normalize(n.split("/", 1)[0].split("-")[0].split(".")[0])
                                  for n in inner.namelist()}:
                        problems.append(f"{wheel.path.name} carries numpy")
    size_mb = zip_path.stat().st_size / 1e6
    if size_mb > max_mb:
        problems.append(f"{size_mb:.1f} MB is over the {max_mb:.0f} MB limit")
    return problems
