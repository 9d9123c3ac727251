"""A read-only, hashable, picklable dict for immutable records (tool paths, machine presets)."""

from __future__ import annotations


class FrozenDict(dict):
    """A dict that refuses changes. Unlike a mappingproxy it pickles (into vector-env workers) and hashes
    (records that hold one stay usable as cache keys; the values must be hashable for that)."""

    def __hash__(self) -> int:  # type: ignore[override]
        return hash(tuple(self.items()))

    def _refuse(self, *args, **kwargs):
        raise TypeError(f"{type(self).__name__} is read-only")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = _refuse  # type: ignore[assignment]
    __ior__ = _refuse  # type: ignore[assignment]

    def __reduce__(self):
        return (type(self), (dict(self),))
