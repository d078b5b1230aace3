"""scripts/fuzz_deep.sh on a small stand-in tree: it finds the contracts by file name, runs each
at the depth asked, prints one line per contract and exits non-zero when one fails."""
import pathlib
import re
import shutil
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "fuzz_deep.sh"

CONTRACT = '''import os
from hypothesis import given, settings, strategies as st

@settings(max_examples=int(os.environ["BD_UV_FUZZ_EXAMPLES"]), database=None)
@given(st.integers())
def test_contract(x):
    assert {check}
'''


def test_fuzz_deep_runs_every_contract_and_fails_when_one_fails(tmp_path):
    (tmp_path / "scripts").mkdir()
    shutil.copy(SCRIPT, tmp_path / "scripts" / "fuzz_deep.sh")
    tests = tmp_path / "tests" / "core"
    tests.mkdir(parents=True)
    (tests / "test_fuzz.py").write_text(CONTRACT.format(check="isinstance(x, int)"))
    (tests / "test_fuzz_boom.py").write_text(CONTRACT.format(check="x < 10"))
    (tests / "test_other.py").write_text("def test_not_a_contract():\n    assert False\n")
    r = subprocess.run(["bash", str(tmp_path / "scripts" / "fuzz_deep.sh"), "7"],
                       capture_output=True, text=True, cwd=tmp_path,
                       env={"PATH": "/usr/bin:/bin", "PYTHON": sys.executable,
                            "FUZZ_LOGS": str(tmp_path / "logs")})
    lines = r.stdout.splitlines()
    assert r.returncode == 1, (r.stdout, r.stderr)
    assert [line.split(":")[0] for line in lines] == ["mesh", "boom"]
    assert re.fullmatch(r"mesh: 7 examples, \d+ s, passed", lines[0])
    assert re.match(r"boom: \d+ examples, \d+ s, FAILED \(exit 1, log .*boom\.log\)", lines[1])
    assert "Falsifying example" in (tmp_path / "logs" / "boom.log").read_text()
    only = subprocess.run(["bash", str(tmp_path / "scripts" / "fuzz_deep.sh"), "3"],
                          capture_output=True, text=True, cwd=tmp_path,
                          env={"PATH": "/usr/bin:/bin", "PYTHON": sys.executable,
                               "FUZZ_ONLY": "mesh"})
    assert only.returncode == 0 and re.fullmatch(r"mesh: 3 examples, \d+ s, passed\n",
                                                 only.stdout)
    bad = subprocess.run(["bash", str(SCRIPT), "many"], capture_output=True, text=True)
    assert bad.returncode == 2 and "usage" in bad.stderr
