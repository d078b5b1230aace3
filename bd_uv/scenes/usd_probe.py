"""A USD file opened first by a separate Python process, so that a file usd-core stops on does not
take the unwrap's process with it.

usd-core reads a damaged crate file (``.usdc``, a ``.usdz``'s root layer) lazily and, on some
corruptions, ends the process instead of raising: a spec of an unknown type copied with the root
layer gave ``FATAL ERROR: Dereferenced an invalid SdfPrimSpec`` and ``abort()`` (found by the
scene fuzz contract, ``tests/core/test_fuzz_scenes.py``: a run of the test suite ended there with
no message). Python cannot catch that, and a crash is not an answer a pipeline can act on.

:func:`probe` therefore runs, in a new interpreter, every usd-core step the unwrap runs on the
input in the order it runs them: the stage opened, every prim (instance proxies and prototypes
too) and the values of its attributes read, its root layer copied into a new layer
(``TransferContent``), its asset paths rewritten and the copy opened as a stage with a primvar
made on each mesh (``usd.UsdScene.write``). A step that raises is noted and the next one runs (the
unwrap's own steps refuse such a file with their messages); a probe that dies is a
``SceneFileError`` naming the file and usd-core's last words. Costs a Python start and an import of
pxr (~0.45 s of CPU) and a second read of the file.
"""
import os
import subprocess
import sys

from ..errors import SceneFileError

# The probe's exit codes: every step ran; a step of the reading raised (the unwrap's reading
# refuses the file with its own message); only the copy raised (refused here, before the unwrap
# runs: its writing would raise the same). A crash is anything else but 1 (a Python error in the
# probe itself: the probe is skipped).
OK, READ_RAISED, COPY_RAISED = 0, 10, 11
# A layer of the stage whose timeCodesPerSecond is 0: usd-core's time scaling between layers
# divides by it, and reading a time-sampled value then never returns (usd-wg/assets'
# stage_configuration/timeCodesPerSecond_0.usda: the unwrap waited for ever). The probe says so
# with this code and the layer, before reading any value.
ZERO_RATE = 12
# The most the probe may take: a file usd-core loops on some other way is refused after it,
# not waited on for ever (reading every value of a large production stage takes seconds to
# a few minutes; the unwrap's own reading takes as long again)
PROBE_SECONDS = 900.0

_SOURCE = r"""
import sys
sys.path.insert(0, sys.argv[1])
from pxr import Sdf, Usd, UsdGeom, UsdUtils
path, raised = sys.argv[2], []


def step(fn):
    try:
        fn()
    except Exception as exc:   # noqa: BLE001 - noted; the unwrap raises its own
        try:
            raised.append(str(exc)[:2000])
        except Exception:   # noqa: BLE001 - a message quoting a corrupted byte
            raised.append(type(exc).__name__)


def values(prims):
    for prim in prims:
        for attr in prim.GetAttributes():
            step(attr.Get)
            step(lambda: [attr.Get(t) for t in attr.GetTimeSamples()[:1]])
        for rel in prim.GetRelationships():
            step(rel.GetTargets)


def read():
    stage = Usd.Stage.Open(path)
    for layer in stage.GetUsedLayers():
        if layer.HasTimeCodesPerSecond() and layer.timeCodesPerSecond == 0:
            sys.stdout.write(layer.realPath or layer.identifier)
            sys.stdout.flush()
            sys.exit(12)
    values(stage.Traverse(Usd.TraverseInstanceProxies()))
    for proto in stage.GetPrototypes():
        values(Usd.PrimRange(proto))
    step(stage.GetUsedLayers)


def copy():
    src = Sdf.Layer.FindOrOpen(path)
    layer = Sdf.Layer.CreateAnonymous(".usdc")
    layer.TransferContent(src)
    step(lambda: UsdUtils.ModifyAssetPaths(layer, lambda p: p))
    stage = Usd.Stage.Open(layer)
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            step(lambda: UsdGeom.PrimvarsAPI(prim).CreatePrimvar(
                "bd_uv_probe", Sdf.ValueTypeNames.TexCoord2fArray))


step(read)
read_raised = bool(raised)
step(copy)
if read_raised:
    sys.exit(10)
if raised:
    sys.stdout.write(raised[0])
    sys.exit(11)
"""


def probe(path):
    """Run usd-core's steps of the unwrap on ``path`` in a new process; raise ``SceneFileError``
    where that process dies. Nothing is checked where no interpreter can be started (an
    embedding without ``sys.executable``) or the probe itself fails to run."""
    import pxr
    exe = sys.executable
    if not exe or not os.path.isfile(exe):
        return
    where = os.path.dirname(os.path.dirname(os.path.abspath(pxr.__file__)))
    try:
        run = subprocess.run([exe, "-c", _SOURCE, where, os.path.abspath(path)],
                             stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, check=False, timeout=PROBE_SECONDS)
    except subprocess.TimeoutExpired:
        raise SceneFileError(f"{path}: usd-core did not finish reading this file in "
                             f"{PROBE_SECONDS:g} s (it loops on some malformed stages); nothing "
                             "was written") from None
    except OSError:
        return
    if run.returncode in (OK, READ_RAISED, 1):
        return
    if run.returncode == ZERO_RATE:
        layer = run.stdout.decode("utf-8", "replace").strip()
        raise SceneFileError(f"{path}: layer {layer} sets timeCodesPerSecond = 0, which "
                             "usd-core cannot read time samples through (it never returns); "
                             "set a positive rate (24 is USD's default) and try again; nothing "
                             "was written")
    if run.returncode == COPY_RAISED:
        said = " ".join(run.stdout.decode("utf-8", "replace").split())
        raise SceneFileError(f"{path}: USD could not copy its root layer to write the UVs, the "
                             f"file is damaged ({said}); nothing was written")
    raise SceneFileError(f"{path}: usd-core stops on this file ({_how(run)}): it is damaged or "
                         "holds something usd-core cannot read; nothing was written")


def _how(run):
    """The probe's end in words: the signal or exit code, and usd-core's fatal error line."""
    code = run.returncode
    if code < 0:
        try:
            import signal
            how = f"killed by {signal.Signals(-code).name}"
        except ValueError:
            how = f"killed by signal {-code}"
    else:
        how = f"exit {code}"
    text = run.stderr.decode("utf-8", "replace")[:20000]
    for line in text.splitlines():
        for mark in ("FATAL ERROR", "Fatal Python error"):
            if mark in line:
                said = " ".join(line[line.index(mark):].split())[:200]
                return f"{how}, {said}"
    return how
