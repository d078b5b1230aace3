"""The extension manifest, the wheel list and build.py's checks, with Blender's own validator.

Blender's validator and builder (``blender_ext.py``) ship inside the ``bpy`` module; ``build.py``
finds and runs them without importing ``bpy``.
"""
import importlib.util
import os
import pathlib
import shutil
import sys
import tomllib
import zipfile

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]


def load_build():
    if "bd_uv_build" in sys.modules:
        return sys.modules["bd_uv_build"]
    spec = importlib.util.spec_from_file_location("bd_uv_build", REPO_ROOT / "build.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bd_uv_build"] = module
    spec.loader.exec_module(module)
    return module


build = load_build()
MANIFEST = tomllib.loads((REPO_ROOT / "blender_manifest.toml").read_text())


def committed_wheels():
    return [build.Wheel(pathlib.Path(w)) for w in MANIFEST["wheels"]]


def test_repo_manifest_passes_blenders_validator():
    out = build.validate(REPO_ROOT)
    assert "Success parsing TOML" in out


def test_validator_rejects_a_broken_manifest(tmp_path):
    # The validator really checks: a 65-character tagline and an unknown license are refused.
    (tmp_path / "__init__.py").write_text("")
    text = (REPO_ROOT / "blender_manifest.toml").read_text()
    bad = text.replace(f'tagline = "{MANIFEST["tagline"]}"', 'tagline = "' + "x" * 65 + '"')
    assert bad != text
    (tmp_path / "blender_manifest.toml").write_text(bad)
    with pytest.raises(build.BuildError, match="tagline"):
        build.validate(tmp_path)


def test_manifest_identity_fields():
    assert MANIFEST["schema_version"] == "1.0.0"
    assert MANIFEST["id"] == "bd_uv"
    assert MANIFEST["version"] == "0.1.0"
    assert MANIFEST["name"] == "Bounded Distortion UV"
    assert 0 < len(MANIFEST["tagline"]) <= 64
    assert MANIFEST["maintainer"] == "bd-uv developers"
    assert MANIFEST["type"] == "add-on"
    assert MANIFEST["blender_version_min"] == "4.2.0"
    assert MANIFEST["license"] == ["SPDX:GPL-3.0-or-later"]
    assert MANIFEST["tags"] == ["UV"]
    assert set(MANIFEST["platforms"]) == {"linux-x64", "windows-x64", "macos-arm64", "macos-x64"}


def test_build_exclusions_keep_development_files_out():
    matcher = build.blender_ext().PathPatternMatch(MANIFEST["build"]["paths_exclude_pattern"])
    for path in ["tests/", "benchmarks/", "docs/", ".ci/", ".git/", ".gitignore", "build.py",
                 "build_extension/", "build_extension/wheels.py", "requirements.txt",
                 "requirements-dev.txt", ".wheel-cache/", "dist/", "out/",
                 "wheels/", "bd_uv/__pycache__/", "bd_uv/mesh/arrays.pyc", "bd_uv/mesh/__pycache__/",
                 "BENCHMARKS.md"]:
        assert matcher.test_path(path), path
    for path in ["__init__.py", "bd_uv/", "bd_uv/mesh/islands.py", "operators/", "ui/", "scripts/",
                 "README.md", "blender_manifest.toml"]:
        assert not matcher.test_path(path), path


def test_committed_wheel_list_matches_the_pins():
    pins_of = {p: build.bundled_pins(build.read_pins(python=p)) for p in build.PYTHONS}
    wheels = committed_wheels()
    assert wheels, "blender_manifest.toml lists no wheels: run python build.py"
    # Only pinned, bundled packages at the version pinned for each Python they serve; never numpy.
    for wheel in wheels:
        served = [p for p in build.PYTHONS if wheel.serves_python(p)]
        assert served, wheel.path.name
        for python in served:
            assert wheel.name in pins_of[python], wheel.path.name
            assert wheel.version == pins_of[python][wheel.name], (wheel.path.name, python)
        assert wheel.name != "numpy"
    for platform in build.PLATFORM_TAGS:
        for python in build.PYTHONS:
            pins = pins_of[python]
            serving = {w.name for w in wheels
                       if platform in w.platforms() and w.serves_python(python)}
            if python == "3.11":
                assert serving == set(pins), (platform, python, set(pins) - serving)
            else:
                # 3.13 support is all or nothing: a partial set would break Blender 5.1+.
                assert serving in (set(pins), set()), (platform, python, set(pins) - serving)
    # scipy is the one binary package pinned per Python: it must have both 3.11 and 3.13 wheels.
    scipy = [w for w in wheels if w.name == "scipy"]
    assert {w.parts[-3] for w in scipy} == {"cp311", "cp313"}
    assert len(scipy) == 2 * len(build.PLATFORM_TAGS)


def test_runtime_pins_match_what_the_zips_bundle():
    pins = build.read_pins()
    assert pins["numpy"] == "1.26.4"  # test / CLI environment only; never bundled
    for name in build.BUNDLED:
        assert build.normalize(name) in pins, name
    assert "numpy" not in map(build.normalize, build.BUNDLED)


def fake_wheel(directory, filename, requires):
    """A minimal wheel file whose METADATA declares ``requires``."""
    name, version = filename.split("-")[:2]
    path = directory / filename
    with zipfile.ZipFile(path, "w") as zf:
        meta = f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n"
        meta += "".join(f"Requires-Dist: {r}\n" for r in requires)
        zf.writestr(f"{name}-{version}.dist-info/METADATA", meta)
        zf.writestr(f"{name}/__init__.py", "")
    return build.Wheel(path)


def test_dependency_check_flags_what_blender_cannot_satisfy(tmp_path):
    ok = fake_wheel(tmp_path, "alpha-1.0-py3-none-any.whl",
                    ["numpy>=1.23.5,<2.5", "beta>=2", "gamma; extra == 'all'",
                     "delta; sys_platform == 'win32'"])
    beta = fake_wheel(tmp_path, "beta-2.1-py3-none-any.whl", [])
    assert build.dependency_problems([ok, beta], "linux-x64", "3.11") == []
    # delta is needed on Windows only, and is not bundled.
    problems = build.dependency_problems([ok, beta], "windows-x64", "3.11")
    assert len(problems) == 1 and "delta" in problems[0]
    # A numpy floor above Blender 4.2's numpy 1.24.3 is refused; the missing beta too.
    new = fake_wheel(tmp_path, "alpha-2.0-py3-none-any.whl", ["numpy>=1.25", "beta>=3"])
    problems = build.dependency_problems([new, beta], "linux-x64", "3.11")
    assert any("1.24.3" in p for p in problems)
    assert any("beta 2.1 is pinned" in p for p in problems)


@pytest.mark.parametrize("python", ["3.11", "3.13"])
def test_real_pinned_wheels_need_nothing_blender_lacks(linux_extension_zips, python):
    # The cached wheels of the pins, downloaded by the zip fixture's build.
    pins = build.bundled_pins(build.read_pins(python=python))
    directory = load_cache_dir("linux-x64", python)
    wheels = [build.Wheel(build.cached_wheel(directory, n, v)) for n, v in pins.items()]
    assert build.dependency_problems(wheels, "linux-x64", python) == []
    # Every bundled wheel's own numpy requirement, read from its metadata, admits the numpy of
    # every Blender version README.md lists for this Python (read here from the README itself).
    from pip._vendor.packaging.requirements import Requirement
    listed = readme_blender_numpy()[python]
    assert listed
    checked = 0
    for wheel in wheels:
        for req in map(Requirement, wheel.requirements()):
            if req.name != "numpy" or req.marker is not None:
                continue
            checked += 1
            for numpy in listed:
                assert req.specifier.contains(numpy), (wheel.path.name, str(req), numpy)
    assert checked >= 3          # scipy, clarabel, trimesh, shapely, qdldl declare numpy
    scipy = next(w for w in wheels if w.name == "scipy")
    spec = next(r for r in map(Requirement, scipy.requirements()) if r.name == "numpy").specifier
    assert not spec.contains("1.23.4")


def readme_blender_numpy():
    """``{python: numpy versions}`` from README.md's Blender table, parsed here (not by build.py)."""
    text = (REPO_ROOT / "README.md").read_text(encoding="utf-8")
    head = text.index("| Blender | Python | numpy |")
    out = {}
    for line in text[head:].splitlines()[2:]:
        if not line.startswith("|"):
            break
        blender, python, numpys = [c.strip() for c in line.strip("|").split("|")]
        out.setdefault(python, []).extend(v.strip() for v in numpys.split(","))
    return out


def test_readme_lists_every_blender_we_claim():
    listed = readme_blender_numpy()
    assert set(listed) == set(build.PYTHONS)
    assert "2.5.5" in listed["3.13"] and "1.24.3" in listed["3.11"]     # Blender 5.2 LTS, 4.2 LTS
    assert {p: set(v) for p, v in build.BLENDER_NUMPY.items()} == {
        p: set(v) for p, v in listed.items()}
    # scipy 1.15.3 (numpy < 2.5) would warn under Blender 5.2: the 3.13 zips must not pin it.
    assert build.read_pins(python="3.13")["scipy"] != "1.15.3"


def load_cache_dir(platform, python):
    cache = pathlib.Path(os.environ.get("BD_UV_WHEEL_CACHE", REPO_ROOT / ".wheel-cache"))
    return cache / platform / f"py{python}"


def test_with_wheels_rewrites_only_the_wheel_block():
    text = (REPO_ROOT / "blender_manifest.toml").read_text()
    new = build.with_wheels(text, ["b-1-py3-none-any.whl", "a-1-py3-none-any.whl"])
    data = tomllib.loads(new)
    assert data["wheels"] == ["./wheels/a-1-py3-none-any.whl", "./wheels/b-1-py3-none-any.whl"]
    assert {k: v for k, v in data.items() if k != "wheels"} == \
        {k: v for k, v in MANIFEST.items() if k != "wheels"}
    assert build.with_wheels(new, [w.path.name for w in committed_wheels()]) == text


@pytest.mark.parametrize("python", ["3.11", "3.13"])
def test_built_zip_passes_validator_and_checks(linux_extension_zips, python):
    path = linux_extension_zips[python]
    out = build.validate(path)
    assert "Success parsing TOML" in out
    with zipfile.ZipFile(path) as zf:
        names = zf.namelist()
        manifest = tomllib.loads(zf.read("blender_manifest.toml").decode())
    assert manifest["build"]["generated"]["platforms"] == ["linux-x64"]
    low, high = {"3.11": ("4.2.0", "5.1.0"), "3.13": ("5.1.0", None)}[python]
    assert manifest["blender_version_min"] == low
    assert manifest.get("blender_version_max") == high
    wheels = sorted(n.split("/", 1)[1] for n in names if n.startswith("wheels/"))
    assert wheels == sorted(w.rsplit("/", 1)[1] for w in manifest["wheels"])
    # Exactly the committed list's wheels that Blender would install on linux-x64 / this Python:
    # one scipy, of this Python only.
    expected = sorted(w.path.name for w in committed_wheels()
                      if "linux-x64" in w.platforms() and w.serves_python(python))
    assert wheels == expected
    tag = "cp" + python.replace(".", "")
    scipy = build.read_pins(python=python)["scipy"]
    assert [w for w in wheels if w.startswith("scipy-")] == [
        w for w in expected if w.startswith(f"scipy-{scipy}-{tag}-{tag}-")]
    assert len([w for w in wheels if w.startswith("scipy-")]) == 1
    assert not [n for n in names if "numpy" in n.lower()]
    assert {n.split("/", 1)[0] for n in names} <= {
        "__init__.py", "blender_manifest.toml", "README.md", "LICENSE", "bd_uv", "operators", "ui",
        "scripts", "wheels"}
    assert "__init__.py" in names and "bd_uv/__init__.py" in names
    assert path.stat().st_size <= 90e6
    assert build.check_zip(path, "linux-x64", python,
                           build.bundled_pins(build.read_pins(python=python)), 90.0) == []


def test_check_zip_catches_what_must_not_ship(tmp_path, linux_extension_zip):
    # build.py's zip check is not vacuous: numpy, a stray file, a wheel for another Python or
    # platform, a missing package and an oversize zip are each reported.
    pins = build.bundled_pins(build.read_pins())
    bad = tmp_path / "bad.zip"
    with zipfile.ZipFile(linux_extension_zip) as src, zipfile.ZipFile(bad, "w") as dst:
        for item in src.infolist():
            if item.filename.startswith("wheels/trimesh-"):
                continue
            data = src.read(item)
            if item.filename == "blender_manifest.toml":
                text = data.decode()
                extra = ["numpy-1.26.4-cp311-cp311-manylinux_2_17_x86_64.whl",
                         "cffi-2.0.0-cp313-cp313-win_amd64.whl"]
                text = text.replace("wheels = [", "wheels = [" + "".join(
                    f'"./wheels/{e}", ' for e in extra), 1)
                data = text.encode()
            dst.writestr(item, data)
        dst.writestr("wheels/numpy-1.26.4-cp311-cp311-manylinux_2_17_x86_64.whl", b"")
        dst.writestr("wheels/cffi-2.0.0-cp313-cp313-win_amd64.whl", b"")
        dst.writestr("notes.txt", "stray")
    problems = "\n".join(build.check_zip(bad, "linux-x64", "3.11", pins, 1.0))
    assert "numpy must never be bundled" in problems
    assert "notes.txt" in problems
    assert "cffi-2.0.0-cp313-cp313-win_amd64.whl is for another platform" in problems
    assert "cffi-2.0.0-cp313-cp313-win_amd64.whl is for another Python" in problems
    assert "no trimesh 4.8.3 wheel" in problems
    assert "over the 1 MB limit" in problems
