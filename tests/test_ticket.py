"""The ticket: what the builder tells a chapter's kernel, read in one place."""

import dataclasses

import pytest

from study.core import ticket
from study.runs import schedule


def test_outside_a_build_there_is_no_ticket(monkeypatch):
    monkeypatch.delenv(ticket.ENV, raising=False)
    assert ticket.current() == ticket.NONE and not ticket.NONE.asked()


def test_a_ticket_reads_back_and_a_rewritten_one_is_read_again(tmp_path, monkeypatch):
    path = ticket.Ticket(results=str(tmp_path / "r.json"), device="cuda").write(tmp_path / "t.json")
    monkeypatch.setenv(ticket.ENV, str(path))
    assert ticket.current().results == str(tmp_path / "r.json") and ticket.current().device == "cuda"
    ticket.Ticket(device="cpu", plan="p.jsonl").write(path)
    assert ticket.current() == ticket.Ticket(device="cpu", plan="p.jsonl")


def test_a_damaged_or_missing_ticket_reads_as_none(tmp_path, monkeypatch):
    monkeypatch.setenv(ticket.ENV, str(tmp_path / "absent.json"))
    assert ticket.current() == ticket.NONE
    (tmp_path / "bad.json").write_text("{not json")
    monkeypatch.setenv(ticket.ENV, str(tmp_path / "bad.json"))
    assert ticket.current() == ticket.NONE


def test_runs_asked_for_in_a_planned_build_are_listed_on_the_ticket(tmp_path, monkeypatch):
    pending = tmp_path / "pending.jsonl"
    t = ticket.Ticket(pending=str(pending))
    monkeypatch.setenv(ticket.ENV, str(t.write(tmp_path / "t.json")))
    assert schedule.planning() == pending and not t.asked()
    pending.write_text('{"dataset": "d.npz"}\n')
    assert t.asked(), "the builder reads the ticket, not the exception, to know the chapter waits for runs"
    with pytest.raises(TypeError):
        dataclasses.replace(t, colour="red")


def test_the_cache_folder_is_the_callers_then_the_builds_then_the_users_then_data(tmp_path, monkeypatch):
    from study.core import datadir

    monkeypatch.delenv(ticket.ENV, raising=False)
    monkeypatch.delenv(datadir.ENV, raising=False)
    assert datadir.resolve() == datadir.DEFAULT and datadir.resolve("") == datadir.DEFAULT
    monkeypatch.setenv(datadir.ENV, str(tmp_path / "mine"))
    assert datadir.resolve() == tmp_path / "mine"
    monkeypatch.setenv(ticket.ENV, str(ticket.Ticket(data_dir=str(tmp_path / "build")).write(tmp_path / "t.json")))
    assert datadir.resolve() == tmp_path / "build" and datadir.resolve(tmp_path / "given") == tmp_path / "given"


def test_a_cache_folder_that_cannot_be_written_is_refused_before_any_work(tmp_path, capsys):
    from study import cli

    (tmp_path / "afile").write_text("not a folder")
    assert cli.main(["book", "--root", str(tmp_path), "--preset", "smoke", "--data-dir",
                     str(tmp_path / "afile" / "data"), "--no-build"]) == 2
    err = capsys.readouterr().err
    assert "cache folder" in err and "afile" in err and len(err.strip().splitlines()) == 1
