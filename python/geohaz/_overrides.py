"""Python values → the `key=value` config overrides the apps take with --set."""
import json
import math
import os


def toml_value(value):
    """A Python value as TOML text: numbers as Python writes them, strings quoted, lists as arrays."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, (str, os.PathLike)):
        return json.dumps(os.fspath(value), ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    try:  # NumPy scalars and arrays
        return toml_value(value.tolist())
    except AttributeError:
        raise TypeError(f"cannot pass a {type(value).__name__} as a config value: {value!r}") from None


def set_overrides(set_):
    """`set=` as a dict {"model.n": 0.08} or a list of "model.n=0.08" strings → list of assignments."""
    if set_ is None:
        return []
    if isinstance(set_, str):
        return [set_]
    if isinstance(set_, dict):
        return [f"{k}={toml_value(v)}" for k, v in set_.items()]
    return [str(s) for s in set_]
