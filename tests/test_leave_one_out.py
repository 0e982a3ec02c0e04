"""Each leave-one-out training is its recipe without one departure, and nothing else (``runs.DEPARTURES``)."""

import json

import pytest

from vgai_lite.lab.runs import (CAMERA_SEED_RUNS, CLEAN_SEED_RUNS, DATA_DIR, DEPARTURES, LEAVE_ONE_OUT,
                                LEAVE_ONE_OUT_CLEAN)
from vgai_lite.vgai_config import BOOK, VGAITrainConfig

CASES = ([(CAMERA_SEED_RUNS[0], d, name) for d, (name, _) in LEAVE_ONE_OUT.items()]
         + [(CLEAN_SEED_RUNS[0], d, name) for d, (name, _) in LEAVE_ONE_OUT_CLEAN.items()])


def stored_config(name: str) -> dict:
    rec = json.loads((DATA_DIR / "experiments" / f"{name}.json").read_text())
    return VGAITrainConfig.from_dict(rec["train_config"]).to_dict()


@pytest.mark.parametrize("recipe_name,departure,name", CASES, ids=[f"{r}-{n}" for r, _, n in CASES])
def test_each_leave_one_out_differs_from_its_recipe_in_its_departure_alone(recipe_name, departure, name):
    recipe, without = stored_config(recipe_name), stored_config(name)
    changed = {k for k in recipe if recipe[k] != without[k]}
    assert changed and changed <= DEPARTURES[departure], (departure, changed)
    assert without["seed"] == recipe["seed"] == 0


def test_the_camera_leave_one_out_starts_from_the_books_recipe():
    assert stored_config(CAMERA_SEED_RUNS[0]) == BOOK.to_dict()
    assert set(LEAVE_ONE_OUT) == set(DEPARTURES), "the leave-one-out through the camera takes back every departure"
    assert set(LEAVE_ONE_OUT_CLEAN) == set(DEPARTURES) - {"the camera model"}


def test_every_leave_one_out_is_flown_on_its_recipes_validation_episodes():
    recs = {name: json.loads((DATA_DIR / "experiments" / f"{name}.json").read_text())
            for _, _, name in CASES}
    recipe = json.loads((DATA_DIR / "experiments" / f"{CAMERA_SEED_RUNS[0]}.json").read_text())
    assert {(r["seed"], r["episodes"]) for r in recs.values()} == {(recipe["seed"], recipe["episodes"])}


def test_every_departure_names_fields_of_the_training_configuration():
    fields = set(VGAITrainConfig().to_dict())
    for departure, names in DEPARTURES.items():
        assert names and names <= fields, departure
