"""The HIL docs a new user follows: every file their commands name exists in
the repository (or is made by an earlier command of the same block), the
example model and host are named, and the candump example shows the
direction field the C runner writes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from c_runner_helpers import RUNNER, command, needs_runner, run, write_log
from hil_helpers import RigDbc, can, gear_model

from gearsim.hil import runner as runner_mod

ROOT = Path(__file__).resolve().parents[3]
DOCS = [ROOT / "docs" / "hil.md", ROOT / "docs" / "hil-runner.md", ROOT / "README.md"]
# a path in the repository: a folder, a slash, a name with a known suffix
REPO_PATH = re.compile(
    r"(?<![\w./-])((?:examples|hil|docs|scripts|tests)/[\w./-]+\.(?:toml|py|dbc|sh))"
)
# the files a command reads: after --model / --params, in Model.load('...'), run by python
READS = re.compile(r"(?:--model\s+|--params\s+|Model\.load\(['\"]|python\s+)(\$?[\w./-]+)")


def _shell_blocks(path: Path) -> list[str]:
    """The sh and python blocks of a doc that run the HIL (all of hil*.md)."""
    blocks = re.findall(r"```(?:sh|python)\n(.*?)```", path.read_text(), re.S)
    if path.name.startswith("hil"):
        return blocks
    return [b for b in blocks if "gearsim hil" in b or "gearsim-hil" in b]


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_doc_commands_use_files_that_exist(doc: Path) -> None:
    if not doc.is_file():
        pytest.skip(f"{doc.name} is not next to the tests")
    blocks = _shell_blocks(doc)
    assert blocks
    made: set[str] = set()  # parameter files an earlier command of the doc wrote
    for block in blocks:
        variables = dict(re.findall(r"^(\w+)=(\S+)$", block, re.M))
        made |= set(re.findall(r"['\"]([\w.-]+\.params)['\"]", block))  # write_params(.., 'x')
        for name in READS.findall(block):
            name = variables.get(name.lstrip("$"), name) if name.startswith("$") else name
            if name in made or name in ("-c", "-m"):
                continue
            assert (ROOT / name).is_file(), f"{doc.name}: {name!r} does not exist"
        for name in REPO_PATH.findall(block):
            assert (ROOT / name).exists(), f"{doc.name}: {name!r} does not exist"


def test_the_examples_are_named_and_run_as_models() -> None:
    text = "\n".join(p.read_text() for p in DOCS if p.is_file())
    for name in ("examples/hil/gear_model.toml", "examples/hil/host.py"):
        assert name in text and (ROOT / name).is_file()
    import gearsim

    model = gearsim.Model.load(ROOT / "examples" / "hil" / "gear_model.toml")
    assert model.block == "simple_gear" and model.rig(dt=1e-3).kind == "simple_gear"


ANSWER = re.compile(r"^\(\d+\.\d{6}\) \w+ [0-9A-F]{3}#(?:[0-9A-F]{2})* T$")


def _candump_example() -> list[str]:
    text = (ROOT / "docs" / "hil-runner.md").read_text()
    section = text[text.index("- **`candump`**") :]
    block = re.search(r"```\n(.*?)```", section, re.S)
    assert block is not None, "no candump example"
    return [line.strip() for line in block.group(1).splitlines() if line.strip()]


def test_the_candump_example_has_the_direction_field() -> None:
    lines = _candump_example()
    assert lines[0].endswith(" R") and lines[-1].endswith(" T")
    assert ANSWER.match(lines[-1]), lines[-1]
    msgs = list(can.CanutilsLogReader(iter(line + "\n" for line in lines)))
    assert [m.is_rx for m in msgs] == [True, False]
    dbc = RigDbc(block="gear")
    assert dbc.database.decode_message(0x100, msgs[0].data)["BaseSpeedCmd"] == 10.0
    fb = dbc.database.decode_message(0x200, msgs[1].data)
    assert (fb["BaseTorque"], fb["BaseSpeed"], fb["LoadTorque"]) == (0.1, 0.0, 0.3)


@needs_runner
def test_the_runner_writes_the_direction_field(tmp_path: Path) -> None:
    """The answers of a replay have the shape of the doc's example line."""
    log = write_log(tmp_path / "in.log", command(RigDbc(block="gear"), 1.7e9, base_speed=10.0))
    params = runner_mod.write_params(gear_model(), tmp_path / "gear.params")
    out = tmp_path / "answers.log"
    res = run(runner_mod.replay_command(params, log, out, tail=0.02, runner=RUNNER))
    assert res.returncode == 0, res.stderr
    lines = out.read_text().splitlines()
    assert lines and all(ANSWER.match(line) for line in lines), lines[:3]


def _campaign_block() -> str:
    text = (ROOT / "docs" / "hil.md").read_text()
    section = text[text.index("## A test campaign") :]
    block = re.search(r"```sh\n(.*?)```", section, re.S)
    assert block is not None, "no commands in 'A test campaign'"
    return block.group(1)


@needs_runner
def test_the_test_campaign_runs_as_written(tmp_path: Path) -> None:
    """docs/hil.md's worked campaign, command for command, in a scratch
    directory: the runner (the tests' build in place of build/hil) serves
    socketcand on a free port, examples/hil/host.py drives it, the verdict has
    the one failure the doc shows, the recording converts and compares, and
    the two replays write the same verdict."""
    import os
    import socket
    import subprocess
    import sys

    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "build" / "hil").mkdir(parents=True)
    (tmp_path / "build" / "hil" / "gearsim-hil").symlink_to(RUNNER)
    with socket.socket() as s:  # a free port in place of the doc's 29536
        s.bind(("127.0.0.1", 0))
        port = str(s.getsockname()[1])
    script = _campaign_block().replace("29536", port)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    res = subprocess.run(
        ["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )
    assert "gearsim-hil exit status 3" in res.stdout, res.stdout + res.stderr
    verdict = (tmp_path / "verdict.xml").read_text()
    assert 'tests="4" failures="1"' in verdict
    assert "never DriveMode == disabled from 2.5 s to 3 s (last: 1)" in verdict
    overall = re.search(r"^overall\s+([0-9.e-]+)", res.stdout, re.M)
    assert overall is not None and float(overall.group(1)) <= 1e-3, res.stdout
    replay_c, replay_py = (
        (tmp_path / "replay-c.xml").read_text(),
        (tmp_path / "replay-py.xml").read_text(),
    )
    assert replay_c == replay_py and 'failures="1"' in replay_c
    # the recording starts with the run (--wait-client): its replay is the live run
    assert replay_c == verdict
