"""One naming rule for the keys of summaries and series columns across the models.

A quantity's name ends in its SI unit, a compound unit written with `_per_`: `max_speed_m_per_s`,
`earthquake_acceleration_m_per_s2`, `discharge_m3_per_s`, `energy_J_per_m` (the form sph-slope and
dem-avalanche already write). Since issue #37 every app writes the rule; folders written before
it (`max_speed_m_s`) are read under the new names, and the old key stays readable, with a
DeprecationWarning, until geohaz 0.2 (docs/python.md, "Migration").
"""
import re
import warnings

# `<name>_m_s` → `<name>_m_per_s` and the like: a length or volume unit, then a time unit.
_OLD_SUFFIX = re.compile(r"_(m|m2|m3)_(s|s2)$")


def canonical(key):
    """The key under the naming rule (unchanged when it already follows it)."""
    return _OLD_SUFFIX.sub(r"_\1_per_\2", key)


class KeyDict(dict):
    """A dict with canonical keys that still answers to the old spelling, with a DeprecationWarning."""

    def __init__(self, items=(), aliases=None):
        super().__init__(items)
        self._aliases = dict(aliases or {})

    def _resolve(self, key):
        if not super().__contains__(key) and key in self._aliases:
            warnings.warn(f"summary key '{key}' is now '{self._aliases[key]}' (docs/python.md, Migration); "
                          "the old name goes in geohaz 0.2", DeprecationWarning, stacklevel=3)
            return self._aliases[key]
        return key

    def __getitem__(self, key):
        return super().__getitem__(self._resolve(key))

    def __contains__(self, key):
        return super().__contains__(key) or key in self._aliases

    def get(self, key, default=None):
        return super().get(self._resolve(key), default)


def canonical_keys(value):
    """A summary (nested dicts and lists, as json.loads gives) with every dict key under the rule."""
    if isinstance(value, dict):
        items, aliases = {}, {}
        for k, v in value.items():
            new = canonical(k)
            items[new] = canonical_keys(v)
            if new != k:
                aliases[k] = new
        return KeyDict(items, aliases)
    if isinstance(value, list):
        return [canonical_keys(v) for v in value]
    return value


# Units of series columns and summary keys, read from the name's suffix (longest first).
_UNITS = [
    ("_m_per_s2", "m/s²"), ("_m3_per_s", "m³/s"), ("_m2_per_s", "m²/s"), ("_m_per_s", "m/s"),
    ("_J_per_m", "J/m"), ("_N_per_m", "N/m"), ("_kN_per_m", "kN/m"), ("_m2_per_m", "m²/m"),
    ("_m3", "m³"), ("_m2", "m²"), ("_m", "m"), ("_s", "s"), ("_pa", "Pa"), ("_Pa", "Pa"), ("_kpa", "kPa"),
    ("_j", "J"), ("_J", "J"), ("_N", "N"), ("_kg", "kg"), ("_deg", "°"), ("_relative", "1"), ("_fraction", "1"),
]


def unit_of(name):
    """The unit a column or key name states by its suffix ("" when it states none)."""
    name = canonical(name)
    for suffix, unit in sorted(_UNITS, key=lambda su: -len(su[0])):
        if name.endswith(suffix) and len(name) > len(suffix):
            return unit
    return ""
