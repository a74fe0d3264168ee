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
