"""What an sdist and a wheel of the Python package carry (scripts/package_check.sh).

    python tests/package/wheel_check.py DIST_DIR

DIST_DIR holds one sdist (gearsim-*.tar.gz) and the wheel built from it
(gearsim-*.whl). Checked:

- the sdist holds the C sources the extension is compiled from, the HIL
  library's among them, and hil/dbc;
- the wheel carries the DBC files as plain files of the package
  gearsim.hil.dbc, byte for byte those of hil/dbc (no link);
- unpacked and imported ahead of any other gearsim, the wheel finds its
  DBCs and its bridge answers a command (the C HIL library is in its
  extension).

Prints one line per check; exit status 1 on the first failure.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import tarfile
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DBCS = ("gear_rig.dbc", "rack_rig.dbc")


def fail(message: str) -> None:
    print(f"wheel_check: {message}", file=sys.stderr)
    raise SystemExit(1)


def one(directory: Path, pattern: str) -> Path:
    found = sorted(directory.glob(pattern))
    if len(found) != 1:
        fail(f"expected one {pattern} in {directory}, found {[p.name for p in found]}")
    return found[0]


def check_sdist(path: Path) -> None:
    with tarfile.open(path) as tar:
        members = {m.name.split("/", 1)[1]: m for m in tar.getmembers() if "/" in m.name}
        needed = ["hil/include/gearsim/hil.h", "hil/src/bridge.c", "hil/src/codec.c"]
        needed += ["hil/src/dbc.c", "include/gearsim/gearsim.h", "setup.py"]
        needed += [f"hil/dbc/{name}" for name in DBCS]
        for name in needed:
            if name not in members or not members[name].isfile():
                fail(f"{path.name} lacks {name} as a file")
        for name in DBCS:
            data = tar.extractfile(members[f"hil/dbc/{name}"]).read()
            if data != (ROOT / "hil" / "dbc" / name).read_bytes():
                fail(f"{path.name}: hil/dbc/{name} differs from the repository's")
    print(f"wheel_check: {path.name} holds hil/src, hil/include and hil/dbc")


def check_wheel(path: Path) -> None:
    with zipfile.ZipFile(path) as whl:
        for name in DBCS:
            member = f"gearsim/hil/dbc/{name}"
            try:
                info = whl.getinfo(member)
            except KeyError:
                fail(f"{path.name} lacks {member}")
            if stat.S_ISLNK(info.external_attr >> 16):
                fail(f"{path.name}: {member} is a link")
            if whl.read(member) != (ROOT / "hil" / "dbc" / name).read_bytes():
                fail(f"{path.name}: {member} differs from hil/dbc/{name}")
    print(f"wheel_check: {path.name} carries gearsim/hil/dbc/*.dbc, identical to hil/dbc")


PROBE = """
import gearsim, gearsim.hil as hil
from gearsim.hil import Bridge, RigDbc, shipped_dbc
from pathlib import Path
here = Path(gearsim.__file__).resolve().parent
for rig in ("gear", "rack"):
    path = shipped_dbc(rig).resolve()
    assert path.is_file() and here in path.parents, (path, here)
dbc = RigDbc(block="gear")
out = []
bridge = Bridge.from_model(gearsim.Model(block="simple_gear"), dbc, send=out.append, stamp=float)
for msg in dbc.encode_command({"cmd.base_speed": 5.0}):
    bridge.handle(msg)
bridge.advance(10)
assert bridge.counters.rx_used == 1 and len(out) == 2, bridge.summary()
print(here)
"""


def check_import(path: Path) -> None:
    with tempfile.TemporaryDirectory(prefix="gearsim-wheel-") as tmp:
        zipfile.ZipFile(path).extractall(tmp)
        env = dict(os.environ, PYTHONPATH=tmp)
        done = subprocess.run(
            [sys.executable, "-c", PROBE], cwd=tmp, env=env, capture_output=True, text=True
        )
        if done.returncode != 0:
            fail(f"the unpacked {path.name} does not run:\n{done.stderr}")
        where = done.stdout.strip()
        if not where.startswith(tmp):
            fail(f"imported gearsim from {where}, not from the wheel")
    print(f"wheel_check: the unpacked {path.name} finds its DBCs and its bridge answers")


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: wheel_check.py DIST_DIR", file=sys.stderr)
        return 2
    dist = Path(argv[1])
    check_sdist(one(dist, "gearsim-*.tar.gz"))
    wheel = one(dist, "gearsim-*.whl")
    check_wheel(wheel)
    check_import(wheel)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
