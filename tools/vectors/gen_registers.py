#!/usr/bin/env python3
"""
Golden vectors for propid's register API codecs and register server, produced by PyCyphal.

Writes core/tests/data/register_payloads.json, checked both ways by core/tests/register_vectors.rs:
  - "encode" cases: fields -> payload_hex (PyCyphal's serializer) and what PyCyphal decodes back;
  - "decode" cases: payload_hex -> decoded (null: PyCyphal rejects it) and PyCyphal's re-encoding, covering
    implicit zero extension (truncated payloads), implicit truncation (oversized payloads), array lengths over
    capacity, union tags past the last member and delimiter headers past the end;
  - "assign" cases: a register of one type, a write of another, and what PyCyphal's register server
    (pycyphal.application._register_server, ValueProxy.assign + Registry) leaves in the register, or null when
    PyCyphal's conversion raises (then its server sends no response; propid answers with the unchanged value);
  - "env" cases: a register and the text of an environment variable, and what PyCyphal's
    ValueProxy.assign_environment_variable makes of it (null: PyCyphal raises, the value is refused).

Types: uavcan.register.{Access,List}.1.0 (request and response), Name.1.0, Value.1.0 (every union member),
uavcan.node.port.List.1.0 (SubjectIDList mask / sparse_list / total, ServiceIDList), uavcan.node.ExecuteCommand.1.3.

How to run (deterministic: no clocks, no random numbers; the output only changes with the code below):
    pip install pycyphal==1.27.1          # brings nunavut 2.3.1, pydsdl 1.25.0, numpy
    python3 tools/vectors/gen_registers.py [--dsdl DIR] [--out FILE] [--compiled DIR]
  --dsdl      folder holding the `uavcan` root namespace (default: the repo's dsdl/ if present, else
              /work/shared/dsdl, the project's shared copy of OpenCyphal public_regulated_data_types)
  --out       output file (default: core/tests/data/register_payloads.json in this repo)
  --compiled  cache for the Python packages PyCyphal generates (default: /tmp/propid_register_vectors)

JSON value notation (what the Rust test parses):
  Value:   {"empty": null} | {"string": HEX} | {"unstructured": HEX} | {"bit": [bool...]}
           | {"integer8".."integer64" / "natural8".."natural64": [int...]}
           | {"real16": [HEX4...]} | {"real32": [HEX8...]} | {"real64": [HEX16...]}  (IEEE bits, big-endian hex)
           reals also carry a human-readable "approx" list next to the member.
  Name:    HEX of the bytes (names need not be UTF-8 on the wire).
  SubjectIDList: {"mask": HEX (1024 bytes)} | {"sparse_list": [int...]} | {"total": null}
  ServiceIDList: HEX (64 bytes)
"""
from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import pathlib
import struct
import sys
import warnings
from typing import Any

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
REPO = HERE.parent.parent


def parse_args() -> argparse.Namespace:
    default_dsdl = REPO / "dsdl"
    if not (default_dsdl / "uavcan").is_dir():
        default_dsdl = pathlib.Path("/work/shared/dsdl")
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dsdl", type=pathlib.Path, default=default_dsdl)
    ap.add_argument("--out", type=pathlib.Path, default=REPO / "core/tests/data/register_payloads.json")
    ap.add_argument("--compiled", type=pathlib.Path, default=pathlib.Path("/tmp/propid_register_vectors"))
    return ap.parse_args()


def compile_dsdl(dsdl: pathlib.Path, out: pathlib.Path) -> None:
    import pycyphal.dsdl

    if not (dsdl / "uavcan").is_dir():
        sys.exit(f"no uavcan namespace under {dsdl}: pass --dsdl")
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "uavcan").is_dir():
        pycyphal.dsdl.compile(dsdl / "uavcan", output_directory=out)
    sys.path.insert(0, str(out))


def ser(obj: Any) -> bytes:
    import pycyphal.dsdl

    return b"".join(bytes(x) for x in pycyphal.dsdl.serialize(obj))


def des(cls: Any, data: bytes) -> Any:
    import pycyphal.dsdl

    return pycyphal.dsdl.deserialize(cls, [memoryview(bytearray(data))])


def type_name(cls: Any) -> str:
    import pycyphal.dsdl

    m = pycyphal.dsdl.get_model(cls)
    ver = f"{m.version.major}.{m.version.minor}"
    for suffix in (".Request", ".Response"):
        if m.full_name.endswith(suffix):
            return f"{m.full_name[: -len(suffix)]}.{ver}{suffix}"
    return f"{m.full_name}.{ver}"


# ----------------------------------------------------------------------------------------------------------------------
# Value <-> JSON
# ----------------------------------------------------------------------------------------------------------------------
INTS = {"integer8": "i1", "integer16": "i2", "integer32": "i4", "integer64": "i8",
        "natural8": "u1", "natural16": "u2", "natural32": "u4", "natural64": "u8"}
REALS = {"real16": (np.float16, np.uint16, 4), "real32": (np.float32, np.uint32, 8), "real64": (np.float64, np.uint64, 16)}


def fj(x: float) -> Any:
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


def member(v: Any) -> str:
    from pycyphal.application.register._value import _get_option_name

    return _get_option_name(v)


def value_json(v: Any) -> dict[str, Any]:
    m = member(v)
    inner = getattr(v, m)
    if m == "empty":
        return {"empty": None}
    if m in ("string", "unstructured"):
        return {m: bytes(inner.value.tobytes()).hex()}
    if m == "bit":
        return {"bit": [bool(x) for x in inner.value]}
    if m in INTS:
        return {m: [int(x) for x in inner.value]}
    ftype, utype, width = REALS[m]
    arr = np.asarray(inner.value, dtype=ftype)
    return {m: [f"{int(b):0{width}x}" for b in arr.view(utype)], "approx": [fj(x) for x in arr]}


def make_value(kind: str, items: Any = None) -> Any:
    """kind and items -> uavcan.register.Value.1.0 (reals are cast by numpy as PyCyphal does)."""
    import uavcan.primitive as P
    import uavcan.primitive.array as A
    import uavcan.register as R

    if kind == "empty":
        return R.Value_1_0(empty=P.Empty_1_0())
    if kind == "string":
        return R.Value_1_0(string=P.String_1_0(items))
    if kind == "unstructured":
        return R.Value_1_0(unstructured=P.Unstructured_1_0(items))
    cls = {"bit": A.Bit_1_0, "integer8": A.Integer8_1_0, "integer16": A.Integer16_1_0, "integer32": A.Integer32_1_0,
           "integer64": A.Integer64_1_0, "natural8": A.Natural8_1_0, "natural16": A.Natural16_1_0,
           "natural32": A.Natural32_1_0, "natural64": A.Natural64_1_0, "real16": A.Real16_1_0,
           "real32": A.Real32_1_0, "real64": A.Real64_1_0}[kind]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpy overflow in float16/float32 casts: that IS PyCyphal's behaviour
        return R.Value_1_0(**{kind: cls(items)})


# ----------------------------------------------------------------------------------------------------------------------
# Other composites -> JSON
# ----------------------------------------------------------------------------------------------------------------------
def name_json(n: Any) -> str:
    return bytes(n.name.tobytes()).hex()


def subject_list_json(s: Any) -> dict[str, Any]:
    if s.mask is not None:
        return {"mask": np.packbits(np.asarray(s.mask, dtype=bool), bitorder="little").tobytes().hex()}
    if s.sparse_list is not None:
        return {"sparse_list": [int(x.value) for x in s.sparse_list]}
    return {"total": None}


def service_list_json(s: Any) -> str:
    return np.packbits(np.asarray(s.mask, dtype=bool), bitorder="little").tobytes().hex()


def to_json(obj: Any) -> Any:
    import uavcan.node as N
    import uavcan.node.port as NP
    import uavcan.register as R

    if isinstance(obj, R.Value_1_0):
        return value_json(obj)
    if isinstance(obj, R.Name_1_0):
        return {"name": name_json(obj)}
    if isinstance(obj, R.Access_1_0.Request):
        return {"name": name_json(obj.name), "value": value_json(obj.value)}
    if isinstance(obj, R.Access_1_0.Response):
        return {"timestamp": int(obj.timestamp.microsecond), "mutable": bool(obj.mutable),
                "persistent": bool(obj.persistent), "value": value_json(obj.value)}
    if isinstance(obj, R.List_1_0.Request):
        return {"index": int(obj.index)}
    if isinstance(obj, R.List_1_0.Response):
        return {"name": name_json(obj.name)}
    if isinstance(obj, NP.List_1_0):
        return {"publishers": subject_list_json(obj.publishers), "subscribers": subject_list_json(obj.subscribers),
                "clients": service_list_json(obj.clients), "servers": service_list_json(obj.servers)}
    if isinstance(obj, N.ExecuteCommand_1_3.Request):
        return {"command": int(obj.command), "parameter": bytes(obj.parameter.tobytes()).hex()}
    if isinstance(obj, N.ExecuteCommand_1_3.Response):
        return {"status": int(obj.status), "output": bytes(obj.output.tobytes()).hex()}
    raise TypeError(type(obj))


# ----------------------------------------------------------------------------------------------------------------------
def build() -> dict[str, Any]:
    import uavcan.node as N
    import uavcan.node.port as NP
    import uavcan.primitive as P
    import uavcan.register as R
    import uavcan.time as T
    from pycyphal.application.register import ValueProxy

    cases: list[dict[str, Any]] = []
    types: dict[str, Any] = {}

    def note_type(cls: Any) -> None:
        import pydsdl
        import pycyphal.dsdl

        m = pycyphal.dsdl.get_model(cls)
        bls = (m.inner_type if isinstance(m, pydsdl.DelimitedType) else m).bit_length_set
        types[type_name(cls)] = {"extent_bytes": m.extent // 8, "sealed": not isinstance(m, pydsdl.DelimitedType),
                                 "min_size_bytes": (min(bls) + 7) // 8, "max_size_bytes": (max(bls) + 7) // 8}

    def enc(name: str, obj: Any) -> None:
        note_type(type(obj))
        payload = ser(obj)
        back = des(type(obj), payload)
        assert back is not None
        cases.append({"type": type_name(type(obj)), "name": name, "kind": "encode", "fields": to_json(obj),
                      "payload_hex": payload.hex(), "decoded": to_json(back)})

    def dec(cls: Any, name: str, payload: bytes) -> None:
        note_type(cls)
        obj = des(cls, payload)
        cases.append({"type": type_name(cls), "name": name, "kind": "decode", "payload_hex": payload.hex(),
                      "payload_len": len(payload), "decoded": None if obj is None else to_json(obj),
                      "reencoded_hex": None if obj is None else ser(obj).hex()})

    # ---------------- Value.1.0: every member, empty, scalar, boundary values, full capacity ----------------
    V = R.Value_1_0
    members: list[tuple[str, list[Any]]] = [
        ("empty", [None]),
        ("string", ["", "uavcan.node.id", "é€𝄞 utf-8", "x" * 256]),
        ("unstructured", [b"", b"\x00\xff\x80", bytes(range(256))]),
        ("bit", [[], [True], [True, False, True, True, False, False, False, False, True], [i % 3 == 0 for i in range(2048)]]),
        ("integer8", [[], [0], [-128, 127, -1, 1], [(i % 256) - 128 for i in range(256)]]),
        ("integer16", [[-32768, 32767, -1], [i * 257 - 32768 for i in range(128)]]),
        ("integer32", [[-(2**31), 2**31 - 1, -1], list(range(-32, 32))]),
        ("integer64", [[-(2**63), 2**63 - 1, -1, 0], [i * 3**30 for i in range(-16, 16)]]),
        ("natural8", [[0, 255], list(range(256))]),
        ("natural16", [[65535], [42], list(range(0, 65535, 516))[:128]]),
        ("natural32", [[0, 2**32 - 1], list(range(64))]),
        ("natural64", [[0, 2**64 - 1, 2**53 + 1], [2**64 - 1 - i for i in range(32)]]),
        ("real16", [[0.0, -0.0, 1.0, 65504.0, -65504.0, 6e-8, float("inf"), float("-inf"), float("nan")],
                    [1e5], [i * 0.1 for i in range(128)]]),
        ("real32", [[0.0, -0.0, 1.5, 3.4028235e38, 1e-45, float("inf"), float("nan")], [1e39],
                    [i / 7 for i in range(64)]]),
        ("real64", [[0.0, -0.0, math.pi, 1.7976931348623157e308, 5e-324, float("-inf"), float("nan")],
                    [i / 3 for i in range(32)]]),
    ]
    for kind, samples in members:
        for k, items in enumerate(samples):
            n = 0 if items is None else len(items)
            enc(f"value {kind} #{k} ({n} elements)", make_value(kind, items))

    # Decode-side Value cases.
    dec(V, "value: empty payload -> tag 0 (empty)", b"")
    dec(V, "value: tag 15 -> rejected", b"\x0f")
    dec(V, "value: tag 255 -> rejected", b"\xff\x01\x00")
    dec(V, "value: string length 257 -> rejected", b"\x01\x01\x01" + b"a" * 257)
    dec(V, "value: string length 256 (full)", b"\x01\x00\x01" + b"b" * 256)
    dec(V, "value: string truncated after 3 of 5 bytes -> zero-extended", b"\x01\x05\x00abc")
    dec(V, "value: natural16 length 129 -> rejected", b"\x0a\x81" + b"\x00" * 258)
    dec(V, "value: natural16 truncated mid-element", b"\x0a\x02\x01\x00\x02")
    dec(V, "value: natural16 with trailing bytes -> ignored", b"\x0a\x01\x2a\x00\xde\xad\xbe\xef")
    dec(V, "value: bit length 2049 -> rejected", b"\x03\x01\x08" + b"\xff" * 300)
    dec(V, "value: bit 3 bits, padding bits set -> ignored", b"\x03\x03\x00\xff")
    dec(V, "value: integer8 length 257 -> rejected", b"\x07\x01\x01" + b"\x80" * 257)
    dec(V, "value: integer64 length 33 -> rejected", b"\x04\x21" + b"\x01" * 300)
    dec(V, "value: real16 raw patterns (sNaN, subnormal, -0)", b"\x0e\x05" + struct.pack("<5H", 0x7C01, 0xFE00, 0x0001, 0x8000, 0x7BFF))
    dec(V, "value: real32 sNaN kept", b"\x0d\x01" + struct.pack("<I", 0x7F800001))
    dec(V, "value: real64 length 0 with trailing garbage", b"\x0c\x00\x99")
    dec(V, "value: unstructured 1 byte, length prefix high byte only", b"\x02\x00")

    # ---------------- Name, Access, List ----------------
    enc("name empty", R.Name_1_0(""))
    enc("name uavcan.node.id", R.Name_1_0("uavcan.node.id"))
    enc("name 255 bytes (max)", R.Name_1_0("n" * 255))
    dec(R.Name_1_0, "name length 255 with 256 bytes -> extra ignored", b"\xff" + b"z" * 256)
    dec(R.Name_1_0, "name truncated -> zero-extended", b"\x04ab")

    AReq, ARes = R.Access_1_0.Request, R.Access_1_0.Response
    enc("access read uavcan.node.id", AReq(R.Name_1_0("uavcan.node.id"), make_value("empty")))
    enc("access write natural16 42", AReq(R.Name_1_0("uavcan.node.id"), make_value("natural16", [42])))
    enc("access write real32 setpoint_rat_lo_hi", AReq(R.Name_1_0("setpoint_rat_lo_hi"), make_value("real32", [0.1, 0.9])))
    enc("access write string description", AReq(R.Name_1_0("uavcan.node.description"), make_value("string", "motor 2")))
    enc("access write max (255-byte name, 256-byte string)", AReq(R.Name_1_0("q" * 255), make_value("string", "s" * 256)))
    enc("access response nonexistent (all empty)", ARes())
    enc("access response natural16 mutable persistent",
        ARes(timestamp=T.SynchronizedTimestamp_1_0(0), mutable=True, persistent=True, value=make_value("natural16", [10])))
    enc("access response immutable, timestamp max 56 bits",
        ARes(timestamp=T.SynchronizedTimestamp_1_0(2**56 - 1), mutable=False, persistent=True, value=make_value("string", "x")))
    enc("access response real64 mutable only",
        ARes(timestamp=T.SynchronizedTimestamp_1_0(123456789), mutable=True, persistent=False, value=make_value("real64", [0.005])))
    enc("access response bit max", ARes(mutable=True, value=make_value("bit", [True] * 2048)))
    dec(AReq, "access request empty payload -> empty name, empty value", b"")
    dec(AReq, "access request name only (value zero-extended to empty)", b"\x03abc")
    dec(AReq, "access request bad value tag -> rejected", b"\x01a\x10")
    dec(ARes, "access response flag byte with void bits set -> ignored", bytes(7) + b"\xff\x0a\x01\x07\x00")
    dec(ARes, "access response truncated inside timestamp", b"\x01\x02\x03")
    dec(ARes, "access response oversized -> extra ignored", bytes(7) + b"\x01\x00" + b"\xaa" * 40)

    LReq, LRes = R.List_1_0.Request, R.List_1_0.Response
    for i in (0, 1, 65535):
        enc(f"list request index {i}", LReq(i))
    enc("list response empty (end)", LRes())
    enc("list response name", LRes(R.Name_1_0("uavcan.pub.sp_rat.id")))
    dec(LReq, "list request 1 byte -> zero-extended", b"\x05")
    dec(LReq, "list request 3 bytes -> extra ignored", b"\x05\x01\xff")
    dec(LRes, "list response length 0 with garbage", b"\x00\x41\x42")

    # ---------------- port.List ----------------
    PL, SL, SV = NP.List_1_0, NP.SubjectIDList_1_0, NP.ServiceIDList_1_0
    SID = NP.SubjectID_1_0

    def svc(ids: list[int]) -> Any:
        m = np.zeros(512, dtype=bool)
        m[ids] = True
        return SV(mask=m)

    def sparse(ids: list[int]) -> Any:
        return SL(sparse_list=[SID(i) for i in ids])

    def mask(ids: list[int]) -> Any:
        m = np.zeros(8192, dtype=bool)
        m[ids] = True
        return SL(mask=m)

    enc("port.List all empty sparse", PL(sparse([]), sparse([]), svc([]), svc([])))
    enc("port.List typical driver", PL(sparse([7509, 7510, 24, 100]), sparse([7509, 110]), svc([384, 385, 430]),
                                       svc([384, 385, 430, 435])))
    enc("port.List mask publishers, total subscribers", PL(mask([0, 1, 8191, 7509, 1234]), SL(total=P.Empty_1_0()),
                                                           svc([0, 511]), svc(list(range(0, 512, 7)))))
    enc("port.List sparse 255 ids (max)", PL(sparse(list(range(0, 8191, 32))[:255]), sparse([8191]), svc([]), svc([])))
    enc("port.List two masks (largest)", PL(mask(list(range(0, 8192, 3))), mask([5]), svc([1]), svc([2])))
    typical = ser(PL(sparse([7509, 24]), sparse([110]), svc([430]), svc([384])))
    dec(PL, "port.List empty payload -> rejected (the first delimiter header runs past the end)", b"")
    dec(PL, "port.List truncated in the servers body -> rejected (header past end)", typical[:-10])
    dec(PL, "port.List oversized -> extra ignored", typical + b"\xee" * 9)
    dec(PL, "port.List bad SubjectIDList tag 3", b"\x01\x00\x00\x00\x03" + typical[9:])
    dec(PL, "port.List sparse count 255 in a 2-byte body -> zero-extended", b"\x02\x00\x00\x00\x01\xff" + typical[10:])
    bigger = bytearray(typical)
    bigger[0] += 2  # publishers body claims two more bytes: they are skipped, the rest is misaligned
    dec(PL, "port.List delimiter header longer than the body (skip unknown bytes)", bytes(bigger))
    shorter = b"\x01\x00\x00\x00\x01" + typical[10:]  # publishers' body was 6 bytes after its header
    dec(PL, "port.List publishers body 1 byte (tag only, sparse count zero-extended)", shorter)
    dec(PL, "port.List typical followed by 4 zero bytes", typical + b"\x00" * 4)
    dec(PL, "port.List cut inside the last delimiter header -> rejected", typical[: len(typical) - 66])
    wide = typical[:-68] + b"\x48\x00\x00\x00" + typical[-64:] + b"\x01\x02\x03\x04\x05\x06\x07\x08"
    dec(PL, "port.List servers body of 72 bytes (a longer future mask) -> truncated to 64", wide)

    # ---------------- ExecuteCommand.1.3 ----------------
    EReq, ERes = N.ExecuteCommand_1_3.Request, N.ExecuteCommand_1_3.Response
    for cmd, param in ((65535, b""), (65530, b""), (65532, b""), (65533, b"/fw/image.bin"), (0, b"\xff" * 255), (32767, b"x")):
        enc(f"execute_command request {cmd} param {len(param)}", EReq(cmd, param))
    for st, out in ((0, b""), (3, b""), (6, b"internal"), (255, b"y" * 46)):
        enc(f"execute_command response status {st} output {len(out)}", ERes(st, out))
    dec(EReq, "execute_command request parameter length 255 in a short payload -> zero-extended", b"\xff\xff\xff" + b"p" * 10)
    dec(EReq, "execute_command request truncated", b"\xfa")
    dec(ERes, "execute_command response 1.1-style (status only)", b"\x03")
    dec(ERes, "execute_command response output 47 -> rejected", b"\x00\x2f" + b"o" * 47)
    dec(ERes, "execute_command response oversized", b"\x00\x01o" + b"\xcc" * 60)

    # ---------------- Register writes, as PyCyphal's register server does them ----------------
    registers = [
        ("natural16", [42]), ("natural16", [1, 2, 3]), ("natural8", [7]), ("natural32", [5, 6]), ("natural64", [9]),
        ("integer8", [-3]), ("integer16", [300, -300]), ("integer32", [0]), ("integer64", [-1]),
        ("real16", [1.5]), ("real32", [0.1, 0.9]), ("real64", [0.005]), ("bit", [True]), ("bit", [False, True]),
        ("string", "motor 2"), ("unstructured", b"\x01\x02"),
    ]
    writes = [
        ("natural16", [1000]), ("natural16", []), ("natural16", [1, 2, 3, 4]), ("natural8", [255]),
        ("natural64", [2**64 - 1]), ("natural32", [70000]), ("integer64", [-1]), ("integer64", [300]),
        ("integer8", [-128, 127]), ("integer16", [-32768]), ("integer32", [2**31 - 1, -(2**31)]),
        ("real64", [2.5]), ("real64", [3.5]), ("real64", [-2.5]), ("real64", [0.1, 0.9]), ("real64", [1e6]),
        ("real64", [1e30]), ("real64", [float("nan")]), ("real64", [float("inf")]), ("real64", [65519.9]),
        ("real32", [0.3]), ("real32", [-0.5]), ("real16", [2.0]), ("real16", [65504.0]),
        ("bit", [True]), ("bit", [False, True, True]), ("string", "42"), ("string", "new text"),
        ("unstructured", b"\xff"), ("empty", None),
    ]
    from pycyphal.application.register import ValueProxy as VP
    for rk, ritems in registers:
        for mutable in (True, False):
            for wk, witems in writes:
                if not mutable and wk not in ("natural16", "string"):
                    continue  # read-only: one write of each broad kind is enough
                reg = make_value(rk, ritems)
                write = make_value(wk, witems)
                # This is RegisterServer._handle_access: assign only if mutable and the write is not empty.
                proxy = VP(reg)
                error = None
                if mutable and member(write) != "empty":
                    try:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            proxy.assign(write)
                            VP(reg).assign(proxy.value)  # Registry.__setitem__ assigns once more
                    except Exception as ex:  # noqa: BLE001 -- any exception: PyCyphal's server does not answer
                        error = type(ex).__name__
                case = {"type": "assign", "name": f"assign {wk} {witems!r:.40} to {'mutable' if mutable else 'read-only'} "
                        f"{rk} {ritems!r:.40}", "kind": "assign", "register": value_json(reg), "mutable": mutable,
                        "write": value_json(write),
                        "result": None if error else value_json(proxy.value)}
                if error:
                    case["pycyphal_exception"] = error
                cases.append(case)

    # ---------------- Register values from environment variables (ValueProxy.assign_environment_variable) -----------
    texts = ["42", "  7   8  ", "2.5", "-1", "1e3", "0.005", "0.1 0.9", "1 2 3 4", "", "abc", "nan", "inf", "-0",
             "300", "65535", "65536", "1.5 x"]
    for rk, ritems in registers:
        for text in texts:
            proxy = VP(make_value(rk, ritems))
            error = None
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    proxy.assign_environment_variable(text)
            except Exception as ex:  # noqa: BLE001
                error = type(ex).__name__
            case = {"type": "env", "name": f"environment {text!r} into {rk} {ritems!r:.40}", "kind": "env",
                    "register": value_json(make_value(rk, ritems)), "text": text,
                    "result": None if error else value_json(proxy.value)}
            if error:
                case["pycyphal_exception"] = error
            cases.append(case)

    return {"generator": generator_info(), "types": types, "cases": cases}


def generator_info() -> dict[str, Any]:
    vers = {}
    for p in ("pycyphal", "nunavut", "pydsdl", "numpy"):
        try:
            vers[p] = importlib.metadata.version(p)
        except importlib.metadata.PackageNotFoundError:
            vers[p] = None
    vers["python"] = sys.version.split()[0]
    return {"tool": "tools/vectors/gen_registers.py", "versions": vers}


def main() -> None:
    args = parse_args()
    compile_dsdl(args.dsdl.resolve(), args.compiled.resolve())
    doc = build()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    kinds: dict[str, int] = {}
    for c in doc["cases"]:
        kinds[c["kind"]] = kinds.get(c["kind"], 0) + 1
    print(f"wrote {args.out}: {len(doc['cases'])} cases {kinds}")


if __name__ == "__main__":
    main()
