"""propid.fit against the command (the same numbers, to the last bit) and against the seed's own
regressor (the cases of host-cli/tests/fit_vs_seed.rs)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import propid
from conftest import REPO, cli


def read_exactly(path) -> pd.DataFrame:
    """pandas' reader with correctly rounded floats (the default from pandas 3 on)."""
    if int(pd.__version__.split(".")[0]) >= 3:
        return pd.read_table(path)
    return pd.read_table(path, float_precision="round_trip")


def cli_fit(path, *flags) -> dict:
    return json.loads(cli(["fit", str(path), "--format", "json", *flags]).stdout)


def test_fit_of_a_path_is_the_commands_json_to_the_last_digit(small_run):
    result = propid.fit(small_run)
    # JSON floats are printed shortest-round-trip: equal dicts are equal f64s, bit for bit.
    assert result.to_dict() == cli_fit(small_run)
    assert result.samples > 1000 and result.mass > 0


def test_bounds_and_diameter_are_the_commands_flags(small_run):
    result = propid.fit(small_run, c1_max=1.0, mass_max=1.5e-5, diameter=0.1778, density=1.2)
    expected = cli_fit(
        small_run, "--c1-max", "1", "--mass-max", "1.5e-5", "--diameter", "0.1778", "--density", "1.2"
    )
    assert result.to_dict() == expected
    # The case exercises a bound (1/θ at θ = 1/1.5e-5 may differ from 1.5e-5 in its last bit).
    assert "mass" in result.at_bound and result.mass == pytest.approx(1.5e-5, rel=1e-15)
    assert result.c_q is not None


def test_a_dataframe_a_dict_and_the_path_give_the_same_answer(small_run):
    by_path = propid.fit(small_run).to_dict()
    frame = propid.read_tsv(small_run)
    assert propid.fit(frame).to_dict() == by_path
    # pandas' own reader (round-trip float parsing) and a dict of plain arrays: same numbers.
    pandas_frame = read_exactly(small_run)
    assert propid.fit(pandas_frame).to_dict() == by_path
    arrays = {c: np.array(frame[c]) for c in ("t", "force", "velocity", "acceleration")}
    assert propid.fit(arrays).to_dict() == by_path


def test_a_file_scanned_in_pieces_agrees_with_its_columns_to_rounding(tmp_path):
    # Over 1 MiB `propid fit` splits the file among threads: the sums are added in another
    # order than the columns' (one piece), so only rounding may differ.
    path = tmp_path / "big.tsv"
    cli(["sim", "--duration", "200", "--rate", "500", "--seed", "2", "--output", str(path)])
    assert path.stat().st_size > 2 << 20
    by_path = propid.fit(path)
    by_frame = propid.fit(propid.read_tsv(path))
    for key in ("mass", "c2", "mass_stderr", "c2_stderr", "rms"):
        a, b = getattr(by_path, key), getattr(by_frame, key)
        assert abs(a - b) <= 1e-12 * abs(a), (key, a, b)
    assert by_path.samples == by_frame.samples and by_path.rows == by_frame.rows


def test_incomplete_rows_are_trimmed_and_announced_as_from_the_file(tmp_path, small_run):
    frame = propid.read_tsv(small_run)
    frame.loc[2000, "velocity"] = np.nan  # breaks the run: the seed fits only what follows
    path = tmp_path / "holed.tsv"
    with open(small_run) as src, open(path, "w") as dst:
        for i, line in enumerate(src):
            if i == 2001:  # data row 2000 is line 2002
                fields = line.split("\t")
                fields[3] = "nan"
                line = "\t".join(fields)
            dst.write(line)
    frame.attrs["source"] = str(path)
    from_file = propid.fit(path)
    assert from_file.to_dict() == cli_fit(path)
    assert from_file.warnings and "line 2002" in from_file.warnings[0]
    assert propid.fit(frame).to_dict() == from_file.to_dict()


def test_predict_acceleration_is_the_seeds_model(small_run):
    r = propid.fit(small_run, c1_max=1.0)
    f, w = np.array([0.01, -0.02]), np.array([100.0, -50.0])
    expected = (f - r.c1 * w - r.c2 * w * np.abs(w)) / r.mass
    assert np.array_equal(r.predict_acceleration(f, w), expected)


# The seed's regressor on the generated cases of host-cli/tests/fit_vs_seed.rs (generator
# arguments, fit options): the same comparison through the Python API.
SEED_CASES = [
    ("0.5 0 0.02 --torque 1,9 --w0 10 --noise 0.5 --nan-head 5", {}),
    ("0.5 0.3 0.02 --torque 1,9 --w0 10 --noise 0.5", {}),
    ("2.0 0 0.05 --torque 2,20 --w0 10 --noise 0.1 --rows 5000 --seed 4", {}),
    ("0.5 0 0.02 --torque 1,9 --w0 10 --noise 0.5 --seed 2", {"mass_max": 0.4}),
    ("1.0 0.2 0.03 --torque 1,9 --w0 10 --noise 0.2 --seed 3", {"c1_max": 1.0}),
]


def make_case(tmp_path, name, generator):
    out = tmp_path / name
    subprocess.run(
        [sys.executable, str(REPO / "tests/seed/make_case.py"), str(out), *generator.split()],
        check=True,
    )
    return out


def seed_fit(path, options):
    flags = [x for k, v in options.items() for x in (f"--{k.replace('_', '-')}", str(v))]
    with open(path) as stdin:
        out = subprocess.run(
            [sys.executable, str(REPO / "tests/seed/dynamics_id_regressor.py"), "--no-plot", *flags],
            stdin=stdin, capture_output=True, text=True, check=True,
        )
    values = dict(line.split(":", 1) for line in out.stdout.splitlines())
    return tuple(float(values[k].split("#")[0]) for k in ("mass", "c1", "c2"))


def sixth_digit(printed):
    """One unit of the sixth significant digit of a printed value (0 for an exact 0)."""
    if printed == 0.0:
        return 0.0
    return 10.0 ** (math.floor(math.log10(abs(printed))) - 5) * (1 + 1e-9)


def rel(a, b):
    return 0.0 if a == b else abs(a - b) / max(abs(a), abs(b))


@pytest.mark.parametrize("generator,options", SEED_CASES)
def test_agrees_with_the_seed_regressor_where_it_converges(tmp_path, generator, options):
    pytest.importorskip("scipy", reason="the seed regressor needs scipy (ci/setup.sh)")
    path = make_case(tmp_path, "case.tsv", generator)
    sm, sc1, sc2 = seed_fit(path, options)
    r = propid.fit(propid.read_tsv(path), **options)
    # The seed prints 6 significant digits: within one unit of the sixth (as fit_vs_seed.rs).
    for printed, exact in [(sm, r.mass), (sc1, r.c1), (sc2, r.c2)]:
        assert abs(printed - exact) <= sixth_digit(printed), (printed, exact)


def test_beats_the_seed_objective_where_the_seed_stalls(tmp_path):
    pytest.importorskip("scipy", reason="the seed regressor needs scipy (ci/setup.sh)")
    path = make_case(tmp_path, "prop.tsv", "2e-5 0 1.5e-8 --noise 50 --nan-head 3")
    sm, sc1, sc2 = seed_fit(path, {})
    r = propid.fit(read_exactly(path))
    out = subprocess.run(
        [sys.executable, str(REPO / "tests/seed/loss.py"), str(path),
         *map(repr, (sm, sc1, sc2, r.mass, r.c1, r.c2))],
        capture_output=True, text=True, check=True,
    )
    seed_loss, our_loss = map(float, out.stdout.split())
    assert our_loss <= seed_loss
    assert rel(r.mass, 2e-5) < 5e-3 and rel(r.c2, 1.5e-8) < 5e-3, (r.mass, r.c2)


def test_the_reading_options_answer_what_the_plausibility_check_asks(small_run):
    # The check names the command's flags; the keywords of the same names answer it.
    frame = propid.read_tsv(small_run)
    truth = propid.fit(frame)
    rpm = frame.copy()
    rpm["velocity"] = rpm["velocity"] * 60 / (2 * np.pi)
    with pytest.raises(propid.CannotJudge, match="--velocity-unit rpm"):
        propid.fit(rpm)
    assert propid.fit(rpm, velocity_unit="rpm").mass == pytest.approx(truth.mass, rel=1e-9)
    flipped = frame.copy()
    flipped["force"] = -flipped["force"]
    with pytest.raises(propid.PropidError, match="--flip-torque"):
        propid.fit(flipped)
    assert propid.fit(flipped, flip_torque=True).mass == pytest.approx(truth.mass, rel=1e-12)
    with pytest.raises(propid.InputError, match="velocity_unit: `furlongs` is not a speed unit"):
        propid.fit(frame, velocity_unit="furlongs")
