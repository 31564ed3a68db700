"""examples/caret-talker-listener: a real CARET architecture file (CARET's early format) imported,
completed, analysed and exported, as its README shows."""
from __future__ import annotations

from verify.cli import main
from verify.core.diagnostics import DiagnosticSink
from verify.interop.caret.read import read
from verify.core.limits import DEFAULT_LIMITS

from .conftest import EXAMPLES

EXAMPLE = EXAMPLES / "caret-talker-listener"


def test_the_import_writes_the_example_file(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(EXAMPLE)
    out = tmp_path / "imported.vfy"
    assert main(["import", "caret", "architecture.yaml", "-o", str(out)]) == 2  # written, but incomplete
    assert out.read_text(encoding="utf-8") == (EXAMPLE / "imported.vfy").read_text(encoding="utf-8")
    err = capsys.readouterr().err
    assert "no executor" in err and "execution times" in err


def test_the_early_format_is_read_with_its_subscriptions_and_publishers():
    path = str(EXAMPLE / "architecture.yaml")
    sink = DiagnosticSink()
    arch = read((EXAMPLE / "architecture.yaml").read_text(encoding="utf-8"), path, sink, DEFAULT_LIMITS)
    assert arch is not None and not sink.items
    nodes = {n.name: n for n in arch.nodes}
    assert [(s.topic, s.callback) for s in nodes["/listener"].subscribes] == [("/chatter", "subscription_callback_0")]
    assert [(p.topic, p.callbacks) for p in nodes["/talker"].publishes] == [("/chatter", ["timer_callback_0"])]
    assert arch.executors == [] and arch.paths == []


def test_a_file_of_neither_format_is_still_refused(tmp_path, capsys):
    path = tmp_path / "architecture.yaml"
    path.write_text("nodes: []\n", encoding="utf-8")
    assert main(["import", "caret", str(path), "-o", str(tmp_path / "x.vfy")]) == 2
    assert "E701" in capsys.readouterr().err and not (tmp_path / "x.vfy").exists()


def test_the_completed_example_is_proved_and_exports_its_chain(tmp_path, capsys):
    completed = str(EXAMPLE / "completed.vfy")
    assert main(["analyze", completed]) == 0
    out = tmp_path / "out"
    assert main(["export", "caret", completed, "-o", str(out)]) == 0
    back = tmp_path / "back.vfy"
    main(["import", "caret", str(out / "architecture.yaml"), "-o", str(back)])  # (incomplete: no wcet)
    text = back.read_text(encoding="utf-8")
    assert "chain chatter: talker.talker_chatter -> listener.subscription_callback_0" in text  # (topic /talker/chatter)


def test_the_chain_exported_into_the_early_file_comes_back(tmp_path, capsys):
    """`export caret --from` the early-format file adds its `named_paths`; importing that file again gives
    the chain, through the same nodes and topic."""
    out = tmp_path / "out"
    assert main(["export", "caret", str(EXAMPLE / "completed.vfy"), "-o", str(out),
                 "--from", str(EXAMPLE / "architecture.yaml")]) == 0
    text = (out / "architecture.yaml").read_text(encoding="utf-8")
    assert text.startswith("named_paths:\n- path_name: chatter\n") and "path_name_aliases: []" in text
    back = tmp_path / "back.vfy"
    main(["import", "caret", str(out / "architecture.yaml"), "-o", str(back)])
    assert "chain chatter: talker.chatter -> listener.subscription_callback_0" in back.read_text(encoding="utf-8")
