#!/usr/bin/env python3
"""Build the bd-uv extension: one zip per platform and Python, each carrying the wheels it needs.

Usage::

    python build.py [--platform linux-x64 ...] [--python 3.11,3.13] [--offline]
                    [--cache .wheel-cache] [--out dist]

Blender 4.2 LTS to 5.0 run Python 3.11; Blender 5.1 and later run Python 3.13. Blender 4.2.0
installs every wheel of its platform listed in a manifest, whatever its Python tag (its wheel filter
carries an upstream to-do note to match Python & ABI tags; the per-Python filter came later), and of
two wheels of the same package and version it keeps the cp313 one: a zip holding both scipy wheels
installs in bpy 4.2.0 and then fails with "The `scipy` install you are using seems to be broken". So
each Python gets its own zip, restricted to its Blender versions through the manifest:

- ``bd_uv-<version>-<platform>.zip``: cp311 wheels, ``blender_version_min = "4.2.0"``,
  ``blender_version_max = "5.1.0"`` (the first version it does not support);
- ``bd_uv-<version>-py313-<platform>.zip``: cp313 wheels, ``blender_version_min = "5.1.0"``.

Steps, for each platform and Python:

1. Download (``pip download --only-binary=:all: --no-deps``) the pinned wheels of every bundled
   package (``BUNDLED``, versions from requirements.txt) into ``<cache>/<platform>/py<version>/``;
   ``--offline`` reuses that cache and never touches the network. A Python for which some package
   has no wheel on that platform is skipped with a warning (3.11 never is). numpy is never bundled:
   Blender ships it, and a bundled copy would shadow Blender's for every add-on.
2. Check every bundled wheel's ``Requires-Dist`` is met inside the zip, or by the numpy Blender
   ships (``BLENDER_NUMPY``).
3. Write the wheel list (all platforms and Pythons) into ``blender_manifest.toml`` when every
   platform and Python is built, and stage a copy of the extension: the repo's files minus the
   manifest's ``[build] paths_exclude_pattern`` (matched by Blender's own code), that platform's and
   Python's wheels, and a manifest listing just those and the Blender versions above.
4. Build the zip with Blender's extension builder (``blender_ext.py build --split-platforms``,
   shipped inside the ``bpy`` module) and run its validator on the zip.
5. Check the zip: each bundled package has a wheel for its platform and Python, no wheel for
   another platform or Python, no numpy anywhere, only the add-on's own top-level entries, the
   Blender version range, and the size (<= ``--max-mb``).

Prints a table of the zips and their sizes; exits non-zero when any check fails.
"""
from __future__ import annotations

import argparse
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path

# The steps live in build_extension/ beside this file (kept out of the zips by the manifest's
# [build] paths_exclude_pattern); found from here however build.py is run or loaded.
if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))

from build_extension.blender_tools import (blender_ext, blender_ext_path,  # noqa: E402
                                           run_blender_ext, validate)
from build_extension.config import (BLENDER_NUMPY, BLENDER_RANGE, BLENDER_ROW,  # noqa: E402
                                    BUNDLED, MANIFEST, MAX_MB, PLATFORM_MARKERS, PLATFORM_TAGS,
                                    PROVIDED_BY_BLENDER, PYTHONS, README, REQUIREMENTS, ROOT,
                                    ZIP_NAME, ZIP_TOP_LEVEL, BuildError, blender_numpy)
from build_extension.manifest import (PLATFORMS_LINE, WHEELS_BLOCK, manifest_data,  # noqa: E402
                                      toml_list, with_blender_range, with_platforms, with_wheels)
from build_extension.wheels import (Wheel, bundled_pins, cached_wheel,  # noqa: E402
                                    dependency_problems, fetch_wheels, marker_env, normalize,
                                    pip_download, read_pins)
from build_extension.zips import check_zip, stage  # noqa: E402

# The names tests and scripts read as build.<name>, wherever they are defined.
__all__ = ["BLENDER_NUMPY", "BLENDER_RANGE", "BLENDER_ROW", "BUNDLED", "MANIFEST", "MAX_MB",
           "PLATFORMS_LINE", "PLATFORM_MARKERS", "PLATFORM_TAGS", "PROVIDED_BY_BLENDER", "PYTHONS",
           "README", "REQUIREMENTS", "ROOT", "WHEELS_BLOCK", "ZIP_NAME", "ZIP_TOP_LEVEL", "Built",
           "BuildError", "Wheel", "blender_ext", "blender_ext_path", "blender_numpy", "build",
           "bundled_pins", "cached_wheel", "check_zip", "dependency_problems", "fetch_wheels",
           "main", "manifest_data", "marker_env", "normalize", "parse_args", "pip_download",
           "print_table", "read_pins", "run_blender_ext", "stage", "toml_list", "validate",
           "with_blender_range", "with_platforms", "with_wheels"]

@dataclass
class Built:
    platform: str
    python: str
    zip_path: Path
    wheels: list[str] = field(default_factory=list)

    @property
    def megabytes(self) -> float:
        return self.zip_path.stat().st_size / 1e6

    @property
    def blender(self) -> str:
        low, high = BLENDER_RANGE[self.python]
        return f"{low} to <{high}" if high else f"{low} and later"


def build(platforms: list[str], pythons: list[str], cache: Path, out: Path, offline: bool,
          max_mb: float, write_manifest: bool) -> list[Built]:
    pins_of = {python: bundled_pins(read_pins(python=python)) for python in pythons}
    wheels: dict[tuple[str, str], list[Wheel]] = {}
    for platform in platforms:
        for python in pythons:
            found = fetch_wheels(platform, python, pins_of[python], cache, offline)
            if found is None:
                continue
            problems = dependency_problems(found, platform, python)
            if problems:
                raise BuildError("unmet wheel requirements:\n  " + "\n  ".join(problems))
            wheels[platform, python] = found
    if not wheels:
        raise BuildError("no wheels for any platform and Python asked for: nothing to build")

    manifest_text = MANIFEST.read_text()
    if write_manifest and set(platforms) == set(PLATFORM_TAGS) and set(pythons) == set(PYTHONS):
        all_names = sorted({w.path.name for ws in wheels.values() for w in ws})
        updated = with_wheels(manifest_text, all_names)
        if updated != manifest_text:
            MANIFEST.write_text(updated)
            print(f"updated the wheel list in {MANIFEST.name} (commit it)")
        manifest_text = updated
    validate(ROOT)

    data = manifest_data(manifest_text)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    failures = []
    for (platform, python), found in wheels.items():
        staged_text = with_blender_range(
            with_platforms(with_wheels(manifest_text, [w.path.name for w in found]), [platform]),
            python)
        stage_dir = out / ".stage" / f"{platform}-py{python}"
        stage(stage_dir, staged_text, found, skip=(out, cache, stage_dir))
        validate(stage_dir)
        name = ZIP_NAME[python].format(id=data["id"], version=data["version"],
                                       platform=platform.replace("-", "_"))
        zip_path = out / name
        if zip_path.exists():
            zip_path.unlink()
        # The builder names a split zip "<output-filepath stem>-<platform>.zip".
        stem = name[:-len(f"-{platform.replace('-', '_')}.zip")] + ".zip"
        run_blender_ext("build", "--source-dir", str(stage_dir),
                        "--output-filepath", str(out / stem), "--split-platforms")
        shutil.rmtree(stage_dir)
        if not zip_path.is_file():
            raise BuildError(f"the builder did not write {zip_path}")
        validate(zip_path)
        problems = check_zip(zip_path, platform, python, pins_of[python], max_mb)
        failures += [f"{zip_path.name}: {p}" for p in problems]
        results.append(Built(platform, python, zip_path, sorted(w.path.name for w in found)))
    stage_root = out / ".stage"
    if stage_root.is_dir() and not any(stage_root.iterdir()):
        stage_root.rmdir()
    print_table(results)
    if failures:
        raise BuildError("zip checks failed:\n  " + "\n  ".join(failures))
    return results


def print_table(results: list[Built]) -> None:
    rows = [("platform", "Python", "Blender", "zip", "MB", "wheels")]
    rows += [(r.platform, r.python, r.blender, r.zip_path.name, f"{r.megabytes:.1f}",
              str(len(r.wheels))) for r in results]
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for i, row in enumerate(rows):
        print("  ".join(cell.rjust(w) if j in (4, 5) else cell.ljust(w)
                        for j, (cell, w) in enumerate(zip(row, widths))).rstrip())
        if i == 0:
            print("  ".join("-" * w for w in widths))


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--platform", action="append", choices=sorted(PLATFORM_TAGS),
                        help="build only this platform (repeatable); default: all four")
    parser.add_argument("--python", default=",".join(PYTHONS),
                        help="comma-separated Pythons to build zips for: 3.11 (Blender 4.2 to "
                             f"5.0), 3.13 (Blender 5.1+); default {','.join(PYTHONS)}")
    parser.add_argument("--offline", action="store_true",
                        help="use only the wheel cache; never run pip download")
    parser.add_argument("--cache", type=Path, default=ROOT / ".wheel-cache",
                        help="wheel cache directory (default .wheel-cache)")
    parser.add_argument("--out", type=Path, default=ROOT / "dist",
                        help="output directory for the zips (default dist)")
    parser.add_argument("--max-mb", type=float, default=MAX_MB,
                        help=f"largest allowed zip, in MB (default {MAX_MB:.0f})")
    parser.add_argument("--no-write-manifest", action="store_true",
                        help="do not update the wheel list in blender_manifest.toml")
    args = parser.parse_args(argv)
    args.python = [p.strip() for p in args.python.split(",") if p.strip()]
    unknown = set(args.python) - set(PYTHONS)
    if unknown or not args.python:
        parser.error(f"--python takes some of {','.join(PYTHONS)}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    platforms = args.platform or list(PLATFORM_TAGS)
    try:
        build(platforms, args.python, args.cache.resolve(), args.out.resolve(), args.offline,
              args.max_mb, not args.no_write_manifest)
    except BuildError as err:
        sys.stdout.flush()
        print(f"build.py: error: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
