"""propid.propulsion is `propid propulsion` in-process: the same result file, from a path or a
DataFrame; CannotJudge carries the result when what was asked is not identified."""

import json

import pytest

import propid
from conftest import cli


def test_propulsion_is_the_commands_result(tmp_path):
    path = tmp_path / "thrust.tsv"
    # C_T = 0.14 on a 7-inch propeller: k = C_T·ρ·D⁴/(2π)².
    cli(["sim", "--duration", "30", "--thrust-k", "4.34e-6", "--output", str(path)])
    out = tmp_path / "cli.json"
    cli(["propulsion", str(path), "--diameter", "7in", "--output", str(out)])
    expected = json.loads(out.read_text())
    assert propid.propulsion(path, diameter="7in") == expected
    # A frame goes through a TSV whose floats read back to the same values: the same result.
    assert propid.propulsion(propid.read_tsv(path), diameter="7in") == expected
    c_t = expected["thrust"]["at_reference"]
    assert c_t["status"] == "identified" and 0.138 < c_t["value"] < 0.142
    # The motor asked for on a log without voltage or current: CannotJudge, the result attached.
    with pytest.raises(propid.CannotJudge, match="the motor") as e:
        propid.propulsion(path, diameter="7in", motor=True)
    assert e.value.result["thrust"]["at_reference"] == c_t
    # A bare 7 is refused, as the command refuses it.
    with pytest.raises(propid.InputError, match="--diameter 7 has no unit"):
        propid.propulsion(path, diameter=7)


# docs/PROPULSION.md §5's question (the command's worked example).
WORKED = dict(c_t=0.14, c_q=0.0107, diameter="7in", thrust="6N", rotors=4, kv=1750,
              resistance="60mohm", no_load_current="0.8A", voltage="4S", battery="3000mAh",
              usable=0.8, density=1.225)


def test_size_is_the_commands_answer(tmp_path):
    flags = [f"--{k.replace('_', '-')}={v}" for k, v in WORKED.items()]
    expected = json.loads(cli(["size", *flags, "--format", "json"]).stdout)
    assert propid.size(**WORKED) == expected
    # From an identified propeller, its dict or its file alike.
    path = tmp_path / "thrust.tsv"
    cli(["sim", "--duration", "30", "--thrust-k", "4.34e-6", "--output", str(path)])
    result = propid.propulsion(path, diameter="7in")
    saved = tmp_path / "prop.json"
    saved.write_text(json.dumps(result))
    by_dict = propid.size(propeller=result, thrust="1N")
    assert by_dict == propid.size(propeller=saved, thrust="1N")
    assert by_dict == json.loads(
        cli(["size", "--propeller", str(saved), "--thrust", "1N", "--format", "json"]).stdout
    )
    with pytest.raises(propid.InputError, match="--diameter 7 has no unit"):
        propid.size(c_t=0.14, c_q=0.0107, diameter=7, thrust="6N")
