"""The JSON Schemas of docs/schemas/ describe the files the twin really writes and ships.

Each schema is checked against files the twin writes (a simulated run's meta.json, a pilot
run, saved configurations) or ships (the demo's configuration, the OMCT bounds, the docs'
examples), each also read by the twin's own reader; and against damaged copies the twin's
reader refuses (a misspelt key, a value out of range), which the schema must refuse too.
"""

import copy
import csv
import json
import re
import tomllib
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator
from referencing import Registry, Resource

from twin.agard.omct import EXAMPLE_BOUNDS, read_bounds
from twin.chain.config import config_names, load_config, motion_system
from twin.cli.main import main
from twin.core.errors import TwinError
from twin.formats.runs import read_run
from twin.formats.schedule import read_schedule
from twin.pilot.models.records import read_pilot_csv
from twin.studies.sweep import parse_grid, read_grid

ROOT = Path(__file__).resolve().parents[1]
SCHEMAS = ROOT / "docs" / "schemas"
EXAMPLES = ROOT / "docs" / "examples"
DEMO_CONFIG = ROOT / "notebooks" / "data" / "srs-imu-filtered.json"

_DOCS = {p.name: json.loads(p.read_text()) for p in sorted(SCHEMAS.glob("*.schema.json"))}
_REGISTRY = Registry().with_resources(
    (doc["$id"], Resource.from_contents(doc)) for doc in _DOCS.values()
)


def validator(name: str) -> Draft202012Validator:
    schema = _DOCS[f"{name}.schema.json"]
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema, registry=_REGISTRY)


def errors(name: str, instance: object) -> list[str]:
    return [e.message for e in validator(name).iter_errors(instance)]


def test_every_schema_is_valid_and_documented():
    assert set(_DOCS) == {
        "twin-config-1.schema.json",
        "twin-run-1-meta.schema.json",
        "twin-pilot-1-row.schema.json",
        "twin-omct-bounds-1.schema.json",
        "twin-sweep.schema.json",
        "twin-schedule-1.schema.json",
    }
    formats = (ROOT / "docs" / "reference" / "formats.md").read_text()
    for name, doc in _DOCS.items():
        Draft202012Validator.check_schema(doc)
        assert doc.get("title") and doc.get("description"), name
        assert f"schemas/{name}" in formats, f"{name} is not shown in reference/formats.md"


# -- twin-config/1 ---------------------------------------------------------------------------


def test_configurations_the_twin_ships_and_saves(tmp_path):
    shipped = json.loads(DEMO_CONFIG.read_text())
    assert errors("twin-config-1", shipped) == []
    for name in config_names():
        saved = motion_system(name).save(tmp_path / f"{name}.json")
        assert errors("twin-config-1", json.loads(saved.read_text())) == [], name
    again = load_config(DEMO_CONFIG).save(tmp_path / "again.json")
    assert errors("twin-config-1", json.loads(again.read_text())) == []


def test_a_configuration_with_physics_and_every_extension(tmp_path):
    data = copy.deepcopy(json.loads(DEMO_CONFIG.read_text()))
    pc = data["platform_config"]
    pc["extensions"] = [
        {"effect": "delay", "parameters": {"extra_delay_s": 0.02}, "dofs": ["pitch"]},
        {"effect": "gain", "parameters": {"gain": 1.2}},
        {"effect": "platform_filter", "parameters": {"break_hz": 3.0}},
        {"effect": "resonance", "parameters": {"frequency_hz": 8.0, "damping": 0.2}},
        {"effect": "lead", "parameters": {"time_constant_s": 0.05}},
        {"effect": "sensor_filter", "parameters": {"cutoff_hz": 3.0, "channels": ["q"]}},
        {"effect": "backlash", "parameters": {"play": 0.001}},
        {"effect": "platform_lag", "parameters": {"lag_s": 0.01}},
        {"effect": "noise", "parameters": {"scale": 2.0}},
        {"effect": "imu_alignment",
         "parameters": {"roll_rad": 0.01, "pitch_rad": 0.0, "yaw_rad": -0.05}},
    ]  # fmt: skip
    pc["physics"] = {
        "legs": {"coulomb_n": [0, 400, 0, 0, 0, 0], "lag_s": 0.002},
        "payload": {"mass_kg": 900, "position_m": [0.4, 0, -0.8], "inertia": [500, 700, 600]},
    }
    path = tmp_path / "full.json"
    path.write_text(json.dumps(data))
    saved = load_config(path).save(tmp_path / "saved.json")  # the twin reads it
    assert errors("twin-config-1", data) == []
    assert errors("twin-config-1", json.loads(saved.read_text())) == []


BAD_CONFIGS = [
    ("misspelt key", lambda d: d["platform_config"].__setitem__("delay", 0.1)),
    ("delay out of range", lambda d: d["platform_config"].__setitem__("delay_s", 11.0)),
    ("unknown effect", lambda d: d["platform_config"]["extensions"][0].__setitem__("effect", "x")),
    ("wrong parameter",
     lambda d: d["platform_config"]["extensions"][0].__setitem__("parameters", {"gain": 2})),
    ("unknown platform", lambda d: d.__setitem__("platform", "vms")),
    ("missing noise", lambda d: d["platform_config"].pop("noise")),
]  # fmt: skip


@pytest.mark.parametrize(("why", "damage"), BAD_CONFIGS, ids=[b[0] for b in BAD_CONFIGS])
def test_the_schema_refuses_what_the_twin_refuses(why, damage, tmp_path):
    data = json.loads(DEMO_CONFIG.read_text())
    damage(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(TwinError):
        load_config(path)
    assert errors("twin-config-1", data), why


# -- twin-run/1 meta.json, twin-pilot/1, twin-schedule/1 -------------------------------------


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Files the twin writes: two simulated runs (a built-in signal, a schedule), a pilot run."""
    out = tmp_path_factory.mktemp("written")
    runs = {
        "multisine": ["simulate", str(DEMO_CONFIG), "--signal", "multisine1-pitch"],
        "schedule": ["simulate", "srs", "--signal", str(EXAMPLES / "schedule.toml")],
    }
    for name, args in runs.items():
        code = main([*args, "--model", "reduced", "--quiet", "--out", str(out / name)])
        assert code == 0, name
    code = main(["pilot", "run", "condition-1", "--quiet", "--out", str(out / "pilot.csv")])
    assert code == 0
    return out


@pytest.mark.parametrize("run", ["multisine", "schedule"])
def test_meta_json_of_runs_the_twin_writes(written, run):
    folder = written / run
    read_run(folder)  # the twin's own reader accepts it
    meta = json.loads((folder / "meta.json").read_text())
    assert errors("twin-run-1-meta", meta) == []
    bad = copy.deepcopy(meta)
    bad["imu"]["position_m"] = [0.0, 0.0]
    assert errors("twin-run-1-meta", bad)


def test_a_pilot_run_the_twin_writes(written):
    path = written / "pilot.csv"
    read_pilot_csv(path)
    with path.open(newline="") as f:
        rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    assert len(rows) > 1000
    v = validator("twin-pilot-1-row")
    assert [e.message for row in rows for e in v.iter_errors(row)] == []
    assert errors("twin-pilot-1-row", {**rows[0], "thetta": 0.0})


def _docstring_schedule() -> str:
    """The example schedule in twin.formats.schedule.toml_schedule's docstring (shipped with it)."""
    text = (ROOT / "twin" / "formats" / "schedule" / "toml_schedule.py").read_text()
    block = re.search(r"\.\. code-block:: toml\n\n(.*?)\n\"\"\"", text, re.S)
    assert block is not None
    return "\n".join(line[4:] for line in block.group(1).splitlines())


def test_schedules_the_twin_ships():
    read_schedule(EXAMPLES / "schedule.toml")
    doc = tomllib.loads((EXAMPLES / "schedule.toml").read_text())
    assert errors("twin-schedule-1", doc) == []
    # the module docstring's example shows every key (its moves are not meant to be played:
    # its constant_speed move starts at a speed the sines before it do not end with)
    assert errors("twin-schedule-1", tomllib.loads(_docstring_schedule())) == []
    doc = tomllib.loads((EXAMPLES / "schedule.toml").read_text())
    doc["move"][1]["frequency_hz"] = doc["move"][1].pop("frequencies_hz")
    assert errors("twin-schedule-1", doc)
    doc = tomllib.loads((EXAMPLES / "schedule.toml").read_text())
    doc["move"][2]["axis"] = [0, 0, 1, 0, 0, 0]  # dof and axis both
    assert errors("twin-schedule-1", doc)


# -- OMCT bounds and sweep files -------------------------------------------------------------


def test_the_omct_bounds_the_twin_ships():
    read_bounds(EXAMPLE_BOUNDS)
    doc = tomllib.loads(Path(EXAMPLE_BOUNDS).read_text())
    assert errors("twin-omct-bounds-1", doc) == []
    del doc["default"]["gain_max"]
    assert errors("twin-omct-bounds-1", doc)


def test_sweep_files():
    read_grid(EXAMPLES / "sweep.toml")
    doc = tomllib.loads((EXAMPLES / "sweep.toml").read_text())
    assert errors("twin-sweep", doc) == []
    text = (ROOT / "twin" / "studies" / "sweep.py").read_text()
    block = re.search(r"points are the product of the axes \(the last axis varies fastest\)::\n\n"
                      r"(.*?)\n\n[A-Z]", text, re.S)  # fmt: skip
    assert block is not None
    docstring = tomllib.loads("\n".join(line[4:] for line in block.group(1).splitlines()))
    parse_grid(docstring)
    assert errors("twin-sweep", docstring) == []
    pilot = {"task": "pilot", "runs": 2, "grid": {"pilot": ["fixed", "adaptive"]}}
    parse_grid(pilot)
    assert errors("twin-sweep", pilot) == []
    for bad in ({**doc, "modle": "full"}, {**doc, "grid": {"pilot": ["fixed"]}}):
        with pytest.raises(TwinError):
            parse_grid(bad)
        assert errors("twin-sweep", bad)
