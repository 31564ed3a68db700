"""`verify report`: one self-contained HTML page, opened in a real headless browser (Debian's Chromium)."""
from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from verify.cli import main

from .conftest import EXAMPLES, in_ci
from .pngpixels import colours

VIOLATED = str(EXAMPLES / "navigation" / "navigation-violated.vfy")
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--enable-logging=stderr", "--v=0"]


def chromium(tmp_path, page, *args: str) -> subprocess.CompletedProcess[str]:
    browser = shutil.which("chromium")
    if browser is None:
        if in_ci():
            pytest.fail("Chromium missing (scripts/install-tools installs it)")
        pytest.skip("Chromium missing")
    profile = tmp_path / f"profile-{len(list(tmp_path.glob('profile-*')))}"
    return subprocess.run(["timeout", "120", browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args,
                           page.as_uri()], capture_output=True, text=True, timeout=180)


def console_messages(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "report.html"
    assert main(["report", VIOLATED, "-o", str(out)]) == 0
    return out


def test_the_page_holds_every_part(report):
    page = report.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>")
    assert '<span class="proved">8 proved</span>, <span class="violated">1 violated</span>' in page
    assert page.count("<svg") == 2  # the diagram and the one counterexample's chart
    assert 'id="diagram"' in page and 'id="outline"' in page and 'id="chains"' in page
    assert "chain reactive: reaction time 160.5 ms against spec 150 ms" in page
    assert "oversampled ×4" in page and "-39.3 ms" in page


def test_the_page_loads_nothing(report):
    page = report.read_text(encoding="utf-8")
    assert "<script" not in page and "<link" not in page
    assert not re.search(r"""(?:\bsrc|\bhref)\s*=\s*["'](?!data:|#)""", page)
    assert not re.search(r"url\(\s*['\"]?(?!data:|#)", page)
    assert "default-src 'none'" in page


def test_the_page_loads_in_a_browser_without_console_errors(report, tmp_path):
    done = chromium(tmp_path, report, "--dump-dom")
    assert done.returncode == 0, done.stderr[-2000:]
    assert console_messages(done.stderr) == []
    assert "<h1>Navigation: timing report</h1>" in done.stdout and 'id="diagram"' in done.stdout


def test_the_console_check_sees_an_error(tmp_path):
    """The check above can fail: a page that asks for a resource is reported on the console."""
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><head><meta http-equiv="Content-Security-Policy" content="default-src '
                   "'none'\"></head><body><img src=\"http://example.invalid/x.png\"></body></html>", encoding="utf-8")
    done = chromium(tmp_path, bad, "--dump-dom")
    assert console_messages(done.stderr)


def test_a_screenshot_shows_the_diagram_the_tables_and_the_chart(report, tmp_path):
    shot = tmp_path / "shot.png"
    done = chromium(tmp_path, report, "--window-size=1200,2400", f"--screenshot={shot}")
    assert done.returncode == 0 and shot.exists(), done.stderr[-2000:]
    seen = colours(shot.read_bytes())
    assert seen[(0x1B, 0x9E, 0x77)] > 500  # the reactive chain's colour: the diagram was drawn
    assert seen[(0xDF, 0xE6, 0xF0)] > 20_000  # table headers (and the diagram's instance headers)
    assert seen[(252, 230, 228)] > 20_000  # the counterexample chart's violating interval


def test_a_system_with_holes_is_refused(tmp_path, capsys):
    holes = str(EXAMPLES / "navigation" / "navigation-holes.vfy")
    assert main(["report", holes, "-o", str(tmp_path / "r.html")]) == 2
    assert "`report` needs a configured system" in capsys.readouterr().err
    assert not (tmp_path / "r.html").exists()


def test_an_existing_file_is_not_overwritten(tmp_path, capsys):
    out = tmp_path / "r.html"
    out.write_text("mine", encoding="utf-8")
    assert main(["report", VIOLATED, "-o", str(out)]) == 2
    assert out.read_text(encoding="utf-8") == "mine" and "refusing to overwrite" in capsys.readouterr().err


def test_without_graphviz_the_page_holds_the_dot_text(tmp_path, monkeypatch):
    import verify.outputs.diagram

    monkeypatch.setattr(verify.outputs.diagram.shutil, "which", lambda name: None)
    out = tmp_path / "r.html"
    assert main(["report", VIOLATED, "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert "Graphviz&#x27;s `dot` is not installed: the diagram's DOT text instead" in page
    assert "digraph &quot;Navigation&quot;" in page and page.count("<svg") == 1


def test_measurements_are_shown_beside_the_bounds_and_load_in_a_browser(tmp_path):
    """`--trace`: CARET's recorded talker and listener (tests/data/caret-traces/) beside their model: a box
    plot per task over its [bcet, wcet], per connection over its delay range, and per chain metric against
    its bound and spec."""
    from .test_trace import COMPLETED, TRACE, require_bindings

    require_bindings()
    out = tmp_path / "measured.html"
    assert main(["report", str(COMPLETED), "-o", str(out), "--trace", str(TRACE)]) == 0
    page = out.read_text(encoding="utf-8")
    section = page.split('<div id="measured">')[1]
    # two tasks and the connection over their model's band; the chain's two metrics against bound and spec
    assert section.count('<g class="measured"') == 5 and section.count('class="model"') == 3
    assert 'class="bound"' in section and 'class="spec"' in section
    assert "max 783.352 us" in section and "error[E801]" in section
    assert "talker.chatter -&gt; listener.chatter" in section and "max 681.328 us" in section
    assert "warning[E807]" in section
    done = chromium(tmp_path, out, "--dump-dom")
    assert done.returncode == 0 and console_messages(done.stderr) == []
    assert 'id="measured"' in done.stdout
