"""Each error of the command is its Python exception, with the command's message."""

from __future__ import annotations

import numpy as np
import pytest

import propid
from conftest import cli_error


def test_the_exceptions_form_one_hierarchy():
    assert issubclass(propid.InputError, propid.PropidError)
    assert issubclass(propid.CannotJudge, propid.PropidError)
    assert issubclass(propid.PropidError, Exception)


def write(path, text):
    path.write_text(text)
    return path


def test_a_missing_file(tmp_path):
    path = tmp_path / "nope.tsv"
    status, message = cli_error(["fit", str(path)])
    assert status == 2
    for call in (propid.fit, propid.read_tsv):
        with pytest.raises(propid.InputError) as e:
            call(path)
        assert str(e.value) == message


def test_a_field_that_is_not_a_number(tmp_path):
    path = write(tmp_path / "bad.tsv", "t\tforce\tvelocity\tacceleration\n0\t1\t2\t3\n0.1\t1\tfoo\t3\n")
    for command, call in [("fit", propid.fit), ("diagnose", propid.diagnose)]:
        status, message = cli_error([command, str(path)])
        assert status == 2 and "line 3" in message and "`velocity`" in message
        with pytest.raises(propid.InputError) as e:
            call(path)
        assert str(e.value) == message
    with pytest.raises(propid.InputError) as e:
        propid.read_tsv(path)
    assert str(e.value) == message


def test_a_missing_column(tmp_path):
    path = write(tmp_path / "cols.tsv", "t\tforce\tacceleration\n0\t1\t3\n")
    status, message = cli_error(["fit", str(path)])
    assert status == 2
    with pytest.raises(propid.InputError) as e:
        propid.fit(path)
    assert str(e.value) == message
    with pytest.raises(propid.InputError, match="missing column `velocity`"):
        propid.fit({"t": [0.0], "force": [1.0], "acceleration": [3.0]})


def test_bounds_that_admit_nothing(small_run):
    status, message = cli_error(["fit", str(small_run), "--mass-min", "2", "--mass-max", "1"])
    assert status == 2
    for data in (small_run, propid.read_tsv(small_run)):
        with pytest.raises(propid.InputError) as e:
            propid.fit(data, mass_min=2, mass_max=1)
        assert str(e.value) == message


def test_too_few_samples(tmp_path):
    rows = "".join(f"{i * 0.01}\t1\t{i}\t2\n" for i in range(5))
    path = write(tmp_path / "short.tsv", "t\tforce\tvelocity\tacceleration\n" + rows)
    status, message = cli_error(["fit", str(path)])
    # Too few samples is the data's limit, not a wrong input: exit 3, as diagnose says it.
    assert status == 3 and "usable samples" in message
    frame = propid.read_tsv(path)
    for data in (path, frame):
        with pytest.raises(propid.CannotJudge) as e:
            propid.fit(data)
        assert str(e.value) == message


def test_data_that_cannot_support_a_verdict(tmp_path):
    rows = "".join(f"{i * 0.002}\t0\t{np.sin(i * 0.01)}\t{np.cos(i * 0.01)}\n" for i in range(5000))
    path = write(tmp_path / "zero.tsv", "t\tforce\tvelocity\tacceleration\n" + rows)
    status, message = cli_error(["diagnose", str(path)])
    assert status == 3
    for data in (path, propid.read_tsv(path)):
        with pytest.raises(propid.CannotJudge) as e:
            propid.diagnose(data)
        assert str(e.value) == message
        assert e.value.diagnosis.verdict == "cannot_judge" and e.value.diagnosis.reasons


def test_a_bad_option_of_simulate_or_plan():
    status, message = cli_error(["sim", "--duration=-5"])
    assert status == 2 and "duration" in message
    with pytest.raises(propid.InputError) as e:
        propid.simulate(duration=-5)
    assert str(e.value) == message
    with pytest.raises(propid.InputError, match="unexpected argument '--no-such-option'"):
        propid.simulate(no_such_option=1)
    with pytest.raises(propid.InputError, match="invalid value 'fast'"):
        propid.simulate(rate="fast")
    status, message = cli_error(["plan", "--max-torque", "0.05"])
    assert status == 2
    with pytest.raises(propid.InputError) as e:
        propid.plan(max_torque=0.05)
    assert str(e.value) == message


def test_importers_refuse_bad_input(tmp_path):
    path = write(tmp_path / "x.csv", "not,a,stand,log\n1,2,3,4\n")
    for command, call in [
        (["import", "rcbench", str(path)], lambda: propid.import_rcbench(path)),
        (["import", "autoquad", str(path), "--kv", "1000"], lambda: propid.import_autoquad(path, kv=1000)),
    ]:
        status, message = cli_error(command)
        assert status == 2
        with pytest.raises(propid.InputError) as e:
            call()
        assert str(e.value) == message


def test_a_wrong_type_of_data_is_a_type_error():
    with pytest.raises(TypeError, match="DataFrame, a dict of arrays or a path"):
        propid.fit(42)  # type: ignore[arg-type]


def test_a_bad_option_of_diagnose_is_the_command_s_error(small_run):
    # The options are the command's flags, parsed by its parser: the same words.
    for flags, options in [
        (["--diameter", "7"], {"diameter": 7}),
        (["--max-effects", "0"], {"max_effects": 0}),
        (["--velocity-unit", "furlongs"], {"velocity_unit": "furlongs"}),
    ]:
        status, message = cli_error(["diagnose", str(small_run), *flags])
        assert status == 2, message
        for data in (small_run, propid.read_tsv(small_run)):
            with pytest.raises(propid.InputError) as e:
                propid.diagnose(data, **options)
            # The command's message (its first paragraph: clap's usage tip names flags).
            assert str(e.value) == message.split("\n\n")[0]
    with pytest.raises(propid.InputError, match="unexpected argument '--no-such-option'"):
        propid.diagnose(small_run, no_such_option=1)
