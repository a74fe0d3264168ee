"""Protocols, learners, camera families and a user's camera paths are each defined once, as records; every other
list of them is derived, so that none can drift from the others (the smoke book's test checks that every one the
experiments write is read back: ``Chapters.unread``)."""

from __future__ import annotations

import dataclasses
import typing

from study import cli
from study.chapters import baselines, engine, motion, table1
from study.learn import protocols
from study.learn.config import TrainConfig
from study.methods import camera_cost, learners, sweep
from study.report import learners as named
from study.report import usercamera
from study.runs import paper
from study.runs.presets import preset
from study.see import paths, scale
from study.simulate import observe


def test_each_chapters_learners_are_the_records_that_name_it_in_their_order():
    assert motion.LEARNERS == named.keys("motion") and engine.LEARNERS == named.keys("engine")
    assert tuple(baselines.METHOD_NAMES) == named.keys("baselines")
    assert motion.NETWORKS == named.keys("motion", "network")
    assert all(motion.NAMES[k] == learners.NAMES[k] == named.WORDS[k] for k in motion.LEARNERS)
    assert len({q.key for q in named.LEARNERS}) == len(named.LEARNERS), "one record a key"


def test_a_protocol_changes_what_its_record_says_and_the_study_protocol_changes_nothing():
    p = preset("smoke")
    plan = paper.protocol_plan(TrainConfig(), p)
    assert [q for q, _ in plan][:: 2 * len(p.protocol_seeds)] == list(protocols.PROTOCOLS)
    for q, cfg in plan:
        base = dataclasses.replace(TrainConfig(), dims=cfg.dims, seed=cfg.seed)
        changed = {f.name for f in dataclasses.fields(cfg) if getattr(cfg, f.name) != getattr(base, f.name)}
        assert changed <= set(q.fields(p.first_patience, p.first_epochs)), q.key
    assert protocols.STUDY.fields(0, 0) == {} and sum(q.study for q in protocols.PROTOCOLS) == 1
    assert typing.get_args(protocols.ProtocolKey) == tuple(q.key for q in protocols.PROTOCOLS)
    assert table1.PROTOCOLS is protocols.PROTOCOLS


def test_the_families_the_sweep_films_are_the_ones_the_results_name_and_any_camera_spans():
    assert list(sweep.FAMILIES) == [f.key for f in observe.CAMERA_FAMILIES]
    assert typing.get_args(usercamera.Family) == ("all", *sweep.FAMILIES)
    r = observe.AnyCameraRanges()
    for f in observe.CAMERA_FAMILIES:
        assert r.height[0] <= f.height[0] and f.height[1] <= r.height[1], f.key
        assert r.distance[0] <= f.distance[0] and f.distance[1] <= r.distance[1], f.key
        assert r.tilt[0] <= f.tilt[0] and f.tilt[1] <= r.tilt[1] and f.yaw[1] <= r.yaw[1], f.key
    assert r.height == (0.3, 2.0) and r.yaw == (-60.0, 60.0), "the span of the families, as the sweep's issue set it"


def test_a_users_paths_are_named_alike_on_the_command_line_in_the_sweep_and_in_the_results():
    assert cli.SCALE_FROM == scale.SCALE_FROM == tuple(camera_cost.ONE_SCALE.values())
    assert cli.SCALE_FROM_DEFAULT == scale.DEFAULT in scale.SCALE_FROM
    assert (*camera_cost.PATHS, camera_cost.FOUND) == tuple(p.words for p in paths.PATHS), "the marks found: apart"
    assert paths.FOUND in paths.FLOOR_KEYS and "floor" in paths.FLOOR_KEYS and len(paths.FLOOR_KEYS) == 2
    assert typing.get_args(paths.PathKey) == (paths.EXACT, paths.KNOWN, *(p.key for p in paths.PATHS))
    from study.chapters import usercamera as page

    assert set(page.PATH_KEYS) == {paths.EXACT, *camera_cost.MEASURED}, "every way the sweep measures has a key"
    assert set(page.PATH_KEYS.values()) == set(typing.get_args(usercamera.SweepKey)), "every key is read back"
    assert set(camera_cost.SCALE) | {camera_cost.FLOOR_PATH} == set(camera_cost.PATHS), "every path has a way to its heights"
