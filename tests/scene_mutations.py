"""Seeded mutations of a scene file for the fuzzer (tests/test_fuzz_scenes.py).

Each mutation is a Mutation(label, data): `data` is the bytes of a scene file that differs
from the original in one way a user (or a broken editor) could get wrong: a wrong type, a
boolean for a number, NaN or inf, zero, negative, huge or tiny values, empty or wrong-length
arrays, a deleted key or table, an unknown key, a table replaced by a value, overlapping or
inverted blocks, a truncated file, binary junk. The mutated scene is written back as TOML
(`to_toml`, inline tables, so any structure can be written, including NaN and inf).
"""

from __future__ import annotations

import copy
import json
import math
import random
import tomllib
from dataclasses import dataclass


@dataclass(frozen=True)
class Mutation:
    label: str
    data: bytes


# -- TOML writer (any nesting; the scene writer of solver.scene needs a well-formed scene) ----
def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(doc: dict) -> str:
    return "".join(f"{json.dumps(k)} = {_value(v)}\n" for k, v in doc.items())


# -- where to mutate -----------------------------------------------------------------------------
def _paths(node, prefix=()):
    """Every key path into a nested dict/list (tables, arrays and leaves)."""
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out.append((*prefix, k))
            out += _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out.append((*prefix, i))
            out += _paths(v, (*prefix, i))
    return out


def _get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def _set(doc, path, value):
    _get(doc, path[:-1])[path[-1]] = value


def _delete(doc, path):
    parent = _get(doc, path[:-1])
    del parent[path[-1]]


def _dotted(path):
    return ".".join(str(p) for p in path)


NUMBERS = {
    "zero": 0,
    "zero float": 0.0,
    "negative": -1.0,
    "negative int": -3,
    "huge": 1e300,
    "huge negative": -1e300,
    "tiny": 1e-300,
    "nan": math.nan,
    "inf": math.inf,
    "-inf": -math.inf,
    "large int": 2**62,
    "one": 1,
    "half": 0.5,
}
WRONG_TYPES = {
    "true": True,
    "false": False,
    "string": "abc",
    "number as string": "0.01",
    "empty string": "",
    "empty array": [],
    "array": [1.0, 2.0],
    "nested array": [[1.0], [2.0, 3.0]],
    "table": {"x": 1},
    "empty table": {},
    "unicode": "\u00e9\u00df\u2603",
}


def _leaf_mutation(doc, path, rng):
    old = _get(doc, path)
    choices = list(NUMBERS.items()) + list(WRONG_TYPES.items())
    if isinstance(old, list):
        choices += [
            ("empty", []),
            ("one short", old[:-1]),
            ("one long", old + (old[-1:] if old else [0.0])),
            ("doubled", old + old),
            ("nested", [old]),
        ]
    if isinstance(old, (int, float)) and not isinstance(old, bool):
        choices += [("negated", -old), ("times 1e6", old * 1e6), ("over 1e6", old / 1e6)]
    name, value = rng.choice(choices)
    _set(doc, path, copy.deepcopy(value))
    return f"{_dotted(path)} = {name}"


def _block_mutation(doc, rng):
    blocks = doc.get("blocks")
    if not isinstance(blocks, list) or not blocks:
        return None
    k = rng.randrange(len(blocks))
    block = blocks[k]
    kind = rng.choice(["overlap", "duplicate", "inverted", "flat", "outside", "polygon", "no shape"])
    if kind in ("overlap", "duplicate"):
        twin = copy.deepcopy(block)
        twin["name"] = f"{block.get('name', 'b')}_twin"
        if kind == "overlap" and "min" in twin and "max" in twin:
            frac = rng.uniform(0.05, 0.95)
            twin["min"] = [lo + frac * (hi - lo) for lo, hi in zip(twin["min"], twin["max"])]
            twin["max"] = [hi + frac * (hi - lo) for lo, hi in zip(block["min"], block["max"])]
        blocks.append(twin)
    elif kind == "inverted" and "min" in block:
        block["min"], block["max"] = block["max"], block["min"]
    elif kind == "flat" and "min" in block:
        block["max"] = list(block["min"])
    elif kind == "outside" and "max" in block:
        block["max"] = [2.0 * abs(v) + 10.0 for v in block["max"]]
    elif kind == "polygon":
        block["shape"] = "polygon"
        rng_pts = rng.choice(
            [[], [[0.0, 0.0]], [[0.0, 0.0], [0.1, 0.0], [0.0, 0.1]], [[0.0, 0.0], [0.1, 0.1]] * 2]
        )
        block["vertices"] = rng_pts
    else:
        block.pop("shape", None)
    return f"blocks[{k}] {kind}"


def _structure_mutation(doc, rng):
    tables = [p for p in _paths(doc) if isinstance(_get(doc, p), (dict, list))]
    kind = rng.choice(["delete table", "table to value", "unknown key", "unknown table"])
    if kind == "unknown table":
        doc[rng.choice(["sceen", "numeric", "output2", "blocks_extra"])] = {"x": 1.0}
        return kind
    path = rng.choice(tables)
    node = _get(doc, path)
    if kind == "delete table":
        _delete(doc, path)
    elif kind == "table to value":
        _set(doc, path, rng.choice([[], 3.0, "table", True, [1, 2]]))
    elif isinstance(node, dict):
        node[rng.choice(["viscosty", "spacng", "x", "MIN", "typical velocity"])] = rng.choice(
            [1.0, "a", True]
        )
    else:
        node.append(rng.choice([1.0, {"name": "x"}, "junk"]))
    return f"{_dotted(path)} {kind}"


def _byte_mutation(text: str, rng):
    data = text.encode()
    kind = rng.choice(["truncated", "binary junk", "junk inserted", "nul byte", "bom", "latin-1", "empty"])
    if kind == "truncated":
        data = data[: rng.randrange(len(data))]
    elif kind == "binary junk":
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 2000)))
    elif kind == "junk inserted":
        at = rng.randrange(len(data))
        data = data[:at] + bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40))) + data[at:]
    elif kind == "nul byte":
        at = rng.randrange(len(data))
        data = data[:at] + b"\x00" + data[at:]
    elif kind == "bom":
        data = b"\xef\xbb\xbf" + data
    elif kind == "latin-1":
        data = data.replace(b"#", "\u00e9 #".encode("latin-1"), 1)
    else:
        data = b""
    return kind, data


def mutations(text: str, n: int, seed: int) -> list[Mutation]:
    """n seeded mutations of the scene `text` (the same n and seed give the same list)."""
    rng = random.Random(seed)
    original = tomllib.loads(text)
    leaves = [p for p in _paths(original) if not isinstance(_get(original, p), (dict, list))]
    arrays = [p for p in _paths(original) if isinstance(_get(original, p), list)]
    out = []
    while len(out) < n:
        doc = copy.deepcopy(original)
        roll = rng.random()
        if roll < 0.10:
            kind, data = _byte_mutation(text, rng)
            out.append(Mutation(kind, data))
            continue
        if roll < 0.55:
            label = _leaf_mutation(doc, rng.choice(leaves), rng)
        elif roll < 0.65:
            label = _leaf_mutation(doc, rng.choice(arrays), rng)
        elif roll < 0.75:
            path = rng.choice(leaves)
            _delete(doc, path)
            label = f"{_dotted(path)} deleted"
        elif roll < 0.87:
            label = _block_mutation(doc, rng) or _structure_mutation(doc, rng)
        else:
            label = _structure_mutation(doc, rng)
        out.append(Mutation(label, to_toml(doc).encode()))
    return out


# -- command-line options ------------------------------------------------------------------------
CLI_MUTATIONS = [
    ["--threads", "0"],
    ["--threads", "-1"],
    ["--threads", "two"],
    ["--threads", "1e3"],
    ["--threads", "100000"],
    ["--threads"],
    ["--set", "="],
    ["--set", "scene.spacing"],
    ["--set", "scene.spacing="],
    ["--set", "scene.spacing=["],
    ["--set", "scene=1"],
    ["--set", "scene.spacing.x=1"],
    ["--set", "blocks.0.name=x"],
    ["--set", "scene.end_time=true"],
    ["--set", "scene.end_time=nan"],
    ["--set", "scene.gravity=[0.0, inf]"],
    ["--set", "\u00e9=1"],
    ["--set", ".=1"],
    ["--set", "materials.water.model=[1]"],
    ["--rebalance-every", "-1"],
    ["--rebalance-every", "x"],
    ["--imbalance-threshold", "nan"],
    ["--imbalance-threshold", "-1"],
    ["--imbalance-threshold", "inf"],
    ["--no-such-option"],
    ["--out"],
    ["--out", ""],
    ["--out", "/proc/scoursph-cannot-write-here"],
    ["--out", "/dev/null"],
]
