"""The benchmark's profiles (``python -m vgai_lite benchmark``): every part timed at every team size."""

from vgai_lite.lab.benchmark import run_flight_profile, run_render_scaling


def test_the_flight_profile_times_every_part_of_a_vgai_step_at_every_team_size():
    rows = run_flight_profile(teams=(8, 16), swarms=1, nearest=5, min_seconds=0.01)
    parts = list(dict.fromkeys(x["part"] for x in rows))
    assert len(parts) == 7 and "panorama and motion frame, 5 nearest" in parts
    assert sorted((x["N"], x["part"]) for x in rows) == sorted((n, p) for n in (8, 16) for p in parts)
    assert all(x["us_per_drone_step"] > 0 for x in rows)


def test_the_render_scaling_times_both_renderers_per_drone_image():
    rows = run_render_scaling(nearest=5, teams=(8, 16), swarms=1, min_seconds=0.01)
    assert [x["N"] for x in rows] == [8, 16] and all(x["all_us"] > 0 and x["nearest_us"] > 0 for x in rows)
