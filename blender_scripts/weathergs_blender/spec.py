"""Strict reading of layout and material parameters: unknown keys and bad values are SpecErrors
that name the scene file and JSON pointer."""

class SpecError(Exception):
    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")
        self.where = where
        self.what = what


def _type_name(v):
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "an object"
    return "null"


class Params:
    """Strict reader of one JSON object: typed getters with defaults, unknown keys are errors."""

    def __init__(self, data, where):
        if not isinstance(data, dict):
            raise SpecError(where, "expected an object, got " + _type_name(data))
        self.data = data
        self.where = where
        self.used = set()

    def _at(self, key):
        return f"{self.where}/{key}"

    def has(self, key):
        return key in self.data

    def num(self, key, default, lo=None, hi=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise SpecError(self._at(key), "expected a number, got " + _type_name(v))
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            raise SpecError(self._at(key), f"expected a number in [{lo}, {hi}], got {v}")
        return float(v)

    def int(self, key, default, lo=0, hi=100000):
        self.used.add(key)
        v = self.data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise SpecError(self._at(key), "expected an integer, got " + _type_name(v))
        if v < lo or v > hi:
            raise SpecError(self._at(key), f"expected an integer in [{lo}, {hi}], got {v}")
        return v

    def vec(self, key, default, n=3, lo=None, hi=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if not isinstance(v, list) or len(v) != n or any(
                isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
            raise SpecError(self._at(key), f"expected an array of {n} numbers")
        if any((lo is not None and x < lo) or (hi is not None and x > hi) for x in v):
            raise SpecError(self._at(key), f"expected values in [{lo}, {hi}]")
        return [float(x) for x in v]

    def str(self, key, default, choices=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if not isinstance(v, str):
            raise SpecError(self._at(key), "expected a string, got " + _type_name(v))
        if choices is not None and v not in choices:
            raise SpecError(self._at(key), f"expected one of {sorted(choices)}, got \"{v}\"")
        return v

    def child(self, key):
        self.used.add(key)
        if key not in self.data:
            raise SpecError(self._at(key), "missing required object")
        return Params(self.data[key], self._at(key))

    def finish(self):
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise SpecError(self._at(unknown[0]), "unknown key (misspelled?)")
