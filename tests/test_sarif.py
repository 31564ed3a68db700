"""SARIF for `check`, `analyze` and `prove`: valid logs, rules with the `verify explain` text as help
(and a helpUri when the distribution names its documentation), and fingerprints that survive lines
added above a result."""
from __future__ import annotations

import json
import shutil

import jsonschema
import pytest

from verify.outputs import sarif
from verify.cli import main
from verify.core.explain import explain

from .conftest import EXAMPLES
from .test_prove import _sarif_schema

NAV = EXAMPLES / "navigation"


def _log(argv, capsys, code) -> dict:
    assert main(argv) == code
    log = json.loads(capsys.readouterr().out)
    jsonschema.Draft4Validator(_sarif_schema()).validate(log)
    return log


@pytest.fixture
def project(tmp_path, monkeypatch):
    for name in ("components.vfy", "navigation.vfy"):
        shutil.copy(NAV / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_analyze_has_sarif_with_the_explain_text_as_help(project, capsys):
    components = project / "components.vfy"
    oa_times = "    bcet 2 ms\n    wcet 8 ms"
    components.write_text(components.read_text().replace(oa_times, "    bcet 2 ms\n    wcet 60 ms", 1))
    log = _log(["analyze", "navigation.vfy", "--format", "sarif"], capsys, 1)
    run = log["runs"][0]
    codes = [r["ruleId"] for r in run["results"]]
    assert "E311" in codes  # (cpu1 overloaded: 60 ms of work every 50 ms)
    rule = next(r for r in run["tool"]["driver"]["rules"] if r["id"] == "E311")
    assert rule["help"]["text"] == explain("E311") == rule["help"]["markdown"]
    assert "helpUri" not in rule  # (no documentation URL in the metadata)
    assert all(r["partialFingerprints"]["verifyFingerprint/v1"] for r in run["results"])
    assert _log(["analyze", str(NAV / "navigation.vfy"), "--format", "sarif"], capsys, 0)["runs"][0]["results"] == []


def test_fingerprints_survive_lines_added_above(project, capsys):
    path = project / "components.vfy"
    text = path.read_text().replace("activation 10 Hz fixed", "activation 100 ms fixed", 1)
    path.write_text(text)
    before = _log(["check", "navigation.vfy", "--format", "sarif"], capsys, 2)["runs"][0]["results"]
    path.write_text("// a comment\n// and another\n\n" + text)
    after = _log(["check", "navigation.vfy", "--format", "sarif"], capsys, 2)["runs"][0]["results"]
    assert [r["locations"][0]["physicalLocation"]["region"]["startLine"] for r in after] == \
        [r["locations"][0]["physicalLocation"]["region"]["startLine"] + 3 for r in before]
    assert [r["partialFingerprints"] for r in after] == [r["partialFingerprints"] for r in before]
    path.write_text(text.replace("activation 100 ms fixed", "activation 200 ms fixed", 1))
    changed = _log(["check", "navigation.vfy", "--format", "sarif"], capsys, 2)["runs"][0]["results"]
    assert [r["partialFingerprints"] for r in changed] != [r["partialFingerprints"] for r in before]


def test_help_uri_from_the_documentation_url(project, capsys, monkeypatch):
    monkeypatch.setattr(sarif, "documentation_uri", lambda: "https://docs.example.org/verify/")
    path = project / "components.vfy"
    path.write_text(path.read_text().replace("activation 10 Hz fixed", "activation 100 ms fixed", 1))
    rules = _log(["check", "navigation.vfy", "--format", "sarif"], capsys, 2)["runs"][0]["tool"]["driver"]["rules"]
    assert [r["helpUri"] for r in rules] == [
        "https://docs.example.org/verify/specs/diagnostics.md#e302-time-where-a-frequency-is-expected-or-vice-versa"]
