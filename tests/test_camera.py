"""Camera triggering: the trigger distance, the MAVLink items, photos and GSD, the presets."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from pymavlink import mavutil, mavwp

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.io import embedded_field
from boustro.io.formats import render
from boustro.mission import plan_area
from boustro.mission.camera import camera_preset, camera_presets, count_photos
from boustro.sensors import Camera

CMD_TRIGG = 206


@pytest.mark.parametrize("front", [0.0, 0.6, 0.75, 0.9])
def test_trigger_distance_gives_the_forward_overlap(front):
    cam = Camera(13.2, 8.8, 5472, altitude=80, image_height=3648, front_overlap=front)
    t = cam.spacing().trigger
    along = 13.2 * 3648 / 5472 * 80 / 8.8  # sensor height (square pixels) x altitude / focal
    assert t.footprint_along == pytest.approx(along)
    # two consecutive photos, one trigger distance apart, overlap by the requested share
    assert (t.footprint_along - t.distance) / t.footprint_along == pytest.approx(front)
    assert t.gsd == pytest.approx(13.2 * 80 / 8.8 / 5472 * 100)


def test_front_overlap_needs_the_image_height_and_a_fraction():
    with pytest.raises(InvalidParameterError, match="image's height"):
        Camera(13.2, 8.8, 5472, altitude=80, front_overlap=0.7).spacing()
    with pytest.raises(InvalidParameterError, match="front overlap"):
        Camera(13.2, 8.8, 5472, altitude=80, image_height=3648, front_overlap=1.0).spacing()


def test_presets_are_complete_and_named():
    presets = camera_presets()
    assert len(presets) >= 5
    for name, p in presets.items():
        assert name == name.lower() and " " not in name
        # the sensor's aspect ratio is the image's (square pixels) within 3%
        ratio = (p["sensor_width_mm"] / p["sensor_height_mm"]) / (
            p["image_width_px"] / p["image_height_px"]
        )
        assert abs(ratio - 1) < 0.03, name
    cam = camera_preset("DJI_Phantom_4_Pro", altitude=100)
    assert (cam.sensor_width, cam.focal_length, cam.image_width) == (13.2, 8.8, 5472)
    with pytest.raises(InvalidParameterError, match="unknown camera"):
        camera_preset("nikon-f")


def _mission(**kw):
    cam = camera_preset("dji-phantom-4-pro", altitude=60, front_overlap=0.8, **kw)
    return plan_area(embedded_field(), cam, speed=8.0)


def _lane_lengths(m):
    plan = m.plan
    return np.hypot(*(plan.transects[:, 1] - plan.transects[:, 0]).T) / plan.ground_scale


def test_photos_along_each_lane():
    m = _mission()
    d = m.camera.distance
    assert d == pytest.approx(12.0)
    expected = sum(math.floor(length / d + 1e-9) + 1 for length in _lane_lengths(m))
    assert m.photos == count_photos(m) == expected
    s = m.summary()["camera"]
    assert s["photos"] == expected and s["gsd_cm_px"] == pytest.approx(1.6447, abs=1e-4)
    assert s["trigger_distance_m"] == pytest.approx(12.0) and s["images_in_turns"] is False
    turns = _mission(images_in_turns=True)
    # through the turns: one stretch over the whole path between the first and last lane ends
    assert turns.photos > m.photos


def _read_wpl(path):
    loader = mavwp.MAVWPLoader()
    loader.load(str(path))
    return [loader.wp(i) for i in range(loader.count())]


def test_waypoints_file_read_by_pymavlink(tmp_path):
    m = _mission()
    path = tmp_path / "m.waypoints"
    path.write_text(render(m, "wpl"))
    items = _read_wpl(path)
    cmds = [w.command for w in items]
    trig = [w for w in items if w.command == CMD_TRIGG]
    n = m.stats.n_transects
    assert len(trig) == 2 * n
    assert [w.param1 for w in trig] == pytest.approx([m.camera.distance, 0.0] * n)
    assert [w.param3 for w in trig] == [1.0, 0.0] * n  # trigger once now at the start
    assert all(w.frame == mavutil.mavlink.MAV_FRAME_MISSION for w in trig)
    # each trigger-on follows a lane's start waypoint, each trigger-off its end waypoint
    navs = [i for i, c in enumerate(cmds) if c == mavutil.mavlink.MAV_CMD_NAV_WAYPOINT][1:]
    kinds = dict(zip(navs, m.kinds, strict=True))
    for i, w in enumerate(items):
        if w.command == CMD_TRIGG:
            assert kinds[i - 1] == ("start" if w.param1 > 0 else "end")


def test_plan_file_follows_qgc_conventions():
    m = _mission(images_in_turns=True)
    doc = json.loads(render(m, "plan"))
    items = doc["mission"]["items"]
    assert [it["doJumpId"] for it in items] == list(range(1, len(items) + 1))
    trig = [it for it in items if it["command"] == CMD_TRIGG]
    # images in turns: on once at the first lane's start, off once at the last lane's end
    assert [it["params"] for it in trig] == [[m.camera.distance, 0, 1, 0, 0, 0, 0], [0] * 7]
    assert all(it["frame"] == 2 and it["type"] == "SimpleItem" for it in trig)
    assert items[0]["command"] == 178  # the speed first


def test_command_line_camera(tmp_path, capsys):
    out = tmp_path / "m.plan"
    args = ["-q", "plan", "--camera", "13.2,8.8,5472,3648", "--altitude", "60"]
    assert main([*args, "--front-overlap", "80", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["camera"]["trigger_distance_m"] == pytest.approx(12.0)
    items = json.loads(out.read_text())["mission"]["items"]
    assert sum(it["command"] == CMD_TRIGG for it in items) == 2 * summary["n_transects"]
    assert main(["plan", "--camera", "sony-rx1r-ii", "--gsd", "1.5", "--json"]) == 0
    assert "camera" not in json.loads(capsys.readouterr().out)  # no front overlap: no trigger
    for bad in (
        [*args[1:], "--images-in-turns"],
        ["plan", "--spacing", "10", "--front-overlap", "70"],
        ["plan", "--camera", "13.2,8.8,5472", "--altitude", "60", "--front-overlap", "70"],
    ):
        assert main(bad) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1
    with pytest.raises(SystemExit) as exc:
        main(["plan", "--camera", "nikon-f", "--altitude", "60"])
    assert exc.value.code == 2
