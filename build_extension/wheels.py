"""The wheels a zip carries: the pins of requirements.txt, downloaded (or found in the cache) per
platform and Python, which Blender platforms and Pythons a wheel installs on (Blender's own
mapping), and their run-time requirements checked against each other and Blender's numpy."""
from __future__ import annotations

import email.parser
import re
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

from .blender_tools import blender_ext
from .config import (BLENDER_NUMPY, BUNDLED, PLATFORM_MARKERS, PLATFORM_TAGS, PROVIDED_BY_BLENDER,
                     PYTHONS, REQUIREMENTS, BuildError)


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
