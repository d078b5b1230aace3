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
import email.parser
import importlib.util
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent
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

WHEELS_BLOCK = re.compile(r"^wheels = \[.*?^\]\n", re.MULTILINE | re.DOTALL)
PLATFORMS_LINE = re.compile(r"^platforms = \[.*?\]\n", re.MULTILINE | re.DOTALL)


class BuildError(Exception):
    """A check failed; the message says which and what to do."""


# -- Blender's extension tooling ------------------------------------------------------------------

def blender_ext_path() -> Path:
    """Path of ``blender_ext.py``, Blender's extension builder/validator inside the ``bpy`` module.

    Found without importing ``bpy`` (that would start Blender).
    """
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise BuildError("the `bpy` module is not installed: pip install -r requirements-dev.txt")
    for location in spec.submodule_search_locations:
        found = sorted(Path(location).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
        if found:
            return found[-1]
    raise BuildError("blender_ext.py not found inside the bpy module")


_BLENDER_EXT = None


def blender_ext():
    """Blender's ``blender_ext`` module (standalone: it imports no ``bpy``)."""
    global _BLENDER_EXT
    if _BLENDER_EXT is None:
        spec = importlib.util.spec_from_file_location("blender_ext", blender_ext_path())
        module = importlib.util.module_from_spec(spec)
        sys.modules["blender_ext"] = module
        spec.loader.exec_module(module)
        _BLENDER_EXT = module
    return _BLENDER_EXT


def run_blender_ext(*args: str) -> str:
    """Run ``blender_ext.py`` with ``args``; its output, or BuildError when it fails."""
    cmd = [sys.executable, str(blender_ext_path()), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise BuildError(f"`blender_ext.py {' '.join(args)}` failed:\n{out}")
    return out


def validate(path: Path) -> str:
    """Blender's validator on an extension directory or zip; BuildError when it rejects it."""
    return run_blender_ext("validate", str(path))


# -- wheels ----------------------------------------------------------------------------------------

def normalize(name: str) -> str:
    """Project name as it appears in wheel filenames (PEP 427/503)."""
    return re.sub(r"[-_.]+", "_", name).lower()


@dataclass(frozen=True)
class Wheel:
    path: Path

    @property
    def parts(self) -> list[str]:
        return self.path.name[:-len(".whl")].split("-")

    @property
    def name(self) -> str:
        return normalize(self.parts[0])

    @property
    def version(self) -> str:
        return self.parts[1]

    @property
    def platform_tag(self) -> str:
        return self.parts[-1]

    @property
    def is_binary(self) -> bool:
        return self.platform_tag != "any"

    def platforms(self) -> set[str]:
        """Blender platforms this wheel installs on (Blender's own mapping)."""
        if not self.is_binary:
            return set(PLATFORM_TAGS)
        found = set()
        for tag in self.platform_tag.split("."):
            found.update(blender_ext().blender_platforms_from_wheel_platform(tag))
        return found

    def serves_python(self, python: str) -> bool:
        """True when Blender would install this wheel in a Blender running ``python``.

        Mirrors Blender's filter: an exact ``cpXY`` tag, a major-only tag (``py3``), or a stable-ABI
        (``abi3``) wheel built for an older or equal Python.
        """
        major, minor = (int(x) for x in python.split("."))
        versions = blender_ext().python_versions_from_wheel_python_tag(self.parts[-3])
        if isinstance(versions, str):
            return False
        stable = blender_ext().python_versions_from_wheel_abi_tag(self.parts[-2], stable_only=True)
        for v in versions:
            if len(v) == 1 and v[0] == major:
                return True
            if len(v) == 2:
                if v == (major, minor):
                    return True
                if not isinstance(stable, str) and (major,) in stable and (major, minor) >= v:
                    return True
        return False

    def requirements(self) -> list[str]:
        """The ``Requires-Dist`` lines of the wheel's METADATA."""
        with zipfile.ZipFile(self.path) as zf:
            meta = next(n for n in zf.namelist()
                        if n.count("/") == 1 and n.endswith(".dist-info/METADATA"))
            msg = email.parser.BytesParser().parsebytes(zf.read(meta))
        return msg.get_all("Requires-Dist") or []


def read_pins(path: Path = REQUIREMENTS, python: str = PYTHONS[0]) -> dict[str, str]:
    """``{normalized name: version}`` of every ``name==version`` line of a requirements file whose
    environment marker (``; python_version >= "3.13"``) holds for ``python``: scipy is pinned per
    Python, so that each Blender gets a scipy whose numpy range includes its numpy."""
    from pip._vendor.packaging.markers import Marker

    pins = {}
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        m = re.fullmatch(r"([A-Za-z0-9][A-Za-z0-9._-]*)\s*==\s*([^\s;]+)\s*(?:;(.*))?", line)
        if m and (m.group(3) is None or Marker(m.group(3)).evaluate(
                {"python_version": python, "python_full_version": python + ".0"})):
            pins[normalize(m.group(1))] = m.group(2)
    return pins


def bundled_pins(pins: dict[str, str]) -> dict[str, str]:
    missing = [n for n in BUNDLED if normalize(n) not in pins]
    if missing:
        raise BuildError(f"requirements.txt pins no version for {', '.join(missing)}")
    bad = [n for n in PROVIDED_BY_BLENDER if normalize(n) in map(normalize, BUNDLED)]
    if bad:
        raise BuildError(f"{bad} must never be bundled: Blender ships it")
    return {normalize(n): pins[normalize(n)] for n in BUNDLED}


def cached_wheel(directory: Path, name: str, version: str) -> Path | None:
    if not directory.is_dir():
        return None
    for path in sorted(directory.glob(f"{name}-{version}-*.whl")):
        return path
    return None


def pip_download(directory: Path, platform: str, python: str, specs: list[str]) -> tuple[bool, str]:
    cmd = [sys.executable, "-m", "pip", "download", "--disable-pip-version-check", "--quiet",
           "--only-binary=:all:", "--no-deps", "--python-version", python,
           "--implementation", "cp", "--dest", str(directory)]
    for tag in PLATFORM_TAGS[platform]:
        cmd += ["--platform", tag]
    proc = subprocess.run(cmd + specs, capture_output=True, text=True)
    return proc.returncode == 0, proc.stdout + proc.stderr


def fetch_wheels(platform: str, python: str, pins: dict[str, str], cache: Path,
                 offline: bool) -> list[Wheel] | None:
    """The bundled wheels for ``platform`` and ``python``, downloading what the cache lacks.

    Returns None (after a warning) when some package has no wheel for this Python; for Python 3.11
    (Blender 4.2 to 5.0) that is an error instead.
    """
    directory = cache / platform / f"py{python}"
    missing = [n for n, v in pins.items() if cached_wheel(directory, n, v) is None]
    if missing and offline:
        if python == PYTHONS[0]:
            raise BuildError(f"--offline: {platform} py{python} wheels of {', '.join(missing)} "
                             f"are not in {directory}; run once without --offline")
        print(f"warning: --offline and no {platform} py{python} wheels of {', '.join(missing)} in "
              f"{directory}: no zip for Blender with Python {python} on {platform}",
              file=sys.stderr)
        return None
    if missing:
        directory.mkdir(parents=True, exist_ok=True)
        ok, out = pip_download(directory, platform, python, [f"{n}=={pins[n]}" for n in missing])
        if not ok:
            # Find out which ones have no wheel, one at a time.
            absent = [n for n in missing
                      if not pip_download(directory, platform, python, [f"{n}=={pins[n]}"])[0]]
            if python == PYTHONS[0] or not absent:
                raise BuildError(f"pip download failed for {platform} py{python}:\n{out}")
            print(f"warning: no {platform} wheel for Python {python} of {', '.join(absent)}: "
                  f"no zip for Blender with Python {python} on {platform}", file=sys.stderr)
            return None
    wheels = [Wheel(cached_wheel(directory, n, v)) for n, v in pins.items()]
    for wheel in wheels:
        if platform not in wheel.platforms() or not wheel.serves_python(python):
            raise BuildError(f"{wheel.path.name} does not install on {platform} / Python {python}")
    return wheels


def marker_env(platform: str, python: str) -> dict[str, str]:
    return {**PLATFORM_MARKERS[platform], "python_version": python,
            "python_full_version": python + ".0", "implementation_name": "cpython",
            "platform_python_implementation": "CPython", "extra": ""}


def dependency_problems(wheels: list[Wheel], platform: str, python: str) -> list[str]:
    """Unmet run-time requirements of ``wheels`` (empty when all are met)."""
    from pip._vendor.packaging.requirements import Requirement

    have = {w.name: w.version for w in wheels}
    env = marker_env(platform, python)
    problems = []
    for wheel in wheels:
        for line in wheel.requirements():
            req = Requirement(line)
            if req.marker is not None and not req.marker.evaluate(env):
                continue  # an extra, or another platform / Python
            name = normalize(req.name)
            if name in map(normalize, PROVIDED_BY_BLENDER):
                for numpy in BLENDER_NUMPY.get(python, ()):
                    if not req.specifier.contains(numpy, prereleases=True):
                        problems.append(f"{wheel.path.name} needs {line}, but Blender ships "
                                        f"numpy {numpy} (Python {python}): pin an older version")
            elif name not in have:
                problems.append(f"{wheel.path.name} needs {line}: add it to BUNDLED and pin it")
            elif not req.specifier.contains(have[name], prereleases=True):
                problems.append(f"{wheel.path.name} needs {line}, but {name} {have[name]} "
                                f"is pinned")
    return problems


# -- manifest --------------------------------------------------------------------------------------

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


# -- staging and checks ----------------------------------------------------------------------------

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


# -- main ------------------------------------------------------------------------------------------

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
