"""The points of a parameter study: stable ids and the study's points made on demand.

A study's grid is a Cartesian product; 40,000 or 10^9 points are never expanded into a
list: :class:`StudyPoints` makes point ``i`` from the axes when it is asked for (mixed
radix, the last axis fastest), so a study starts its first point at once and holds
memory of the size of its axes, not of its product.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, overload

#: status of a point: no finished/failed summary yet, executing, done, failed
PENDING, RUNNING, FINISHED, FAILED = "pending", "running", "finished", "failed"


def canonical_json(params: Mapping[str, Any]) -> str:
    """The parameters as sorted, compact JSON (floats in shortest round-trip form)."""
    return json.dumps(dict(params), sort_keys=True, separators=(",", ":"))


def slug_value(v: Any) -> str:
    """A parameter value as a short file-name-safe string (``0.02``, ``1e+06``)."""
    s = f"{v:g}" if isinstance(v, float) else str(v)
    return re.sub(r"[^A-Za-z0-9.+-]", "_", s)


def point_id(params: Mapping[str, Any], varied: Sequence[str]) -> str:
    """Stable folder name: slug of the varied parameters (sorted by name, so reordering
    the study file keeps the ids) + 10 hex digits of the sha256 of all parameters."""
    digest = hashlib.sha256(canonical_json(params).encode()).hexdigest()[:10]
    slug = "_".join(f"{k}={slug_value(params[k])}" for k in sorted(varied) if k in params)
    slug = slug[:80].rstrip("_")
    return f"{slug}-{digest}" if slug else digest


@dataclass(frozen=True)
class StudyPoint:
    """One simulation of a study: its stable id and its full parameter set (fixed + varied)."""

    id: str
    params: dict[str, Any]


def merge(fixed: Mapping[str, Any], point: Mapping[str, Any]) -> dict[str, Any]:
    """A point's full parameters: the fixed ones it does not set, then its own."""
    return {**{k: v for k, v in fixed.items() if k not in point}, **point}


class StudyPoints(Sequence[StudyPoint]):
    """The points of a study in study order: the grid's Cartesian product (the axes in the
    order written, the last fastest), then the listed points, each made when asked for.

    ``axes``: name -> distinct values (duplicates removed by the caller: the product of
    the distinct values is the product with repeats removed, in the same order);
    ``listed``: explicit points (their own parameters, without the fixed ones), none of
    them equal to a grid point or to another. Length, indexing, slicing, iteration and
    :meth:`index` (the position of a parameter set) cost the size of the axes, never of
    the product.
    """

    def __init__(self, fixed: Mapping[str, Any], axes: Mapping[str, Sequence[Any]],
                 listed: Sequence[Mapping[str, Any]], varied: Sequence[str]) -> None:
        self.fixed = dict(fixed)
        self.axes = {k: tuple(v) for k, v in axes.items()}
        self.listed = tuple(merge(self.fixed, p) for p in listed)
        self.varied = tuple(varied)
        self.n_grid = math.prod(len(v) for v in self.axes.values()) if self.axes else 0
        # position of each axis value (by canonical JSON, as the point ids compare them)
        self._slot = {k: {_key(v): i for i, v in enumerate(vals)}
                      for k, vals in self.axes.items()}
        self._listed_at = {canonical_json(p): i for i, p in enumerate(self.listed)}

    def __len__(self) -> int:
        return self.n_grid + len(self.listed)

    def params_at(self, i: int) -> dict[str, Any]:
        """Parameters of point ``i`` (0 <= i < len)."""
        if i < self.n_grid:
            combo = {}
            for k in reversed(self.axes):
                vals = self.axes[k]
                i, r = divmod(i, len(vals))
                combo[k] = vals[r]
            return merge(self.fixed, {k: combo[k] for k in self.axes})
        return dict(self.listed[i - self.n_grid])

    def make(self, params: dict[str, Any]) -> StudyPoint:
        """The point of these parameters (its id from :func:`point_id`)."""
        return StudyPoint(point_id(params, self.varied), params)

    @overload
    def __getitem__(self, i: int) -> StudyPoint: ...

    @overload
    def __getitem__(self, i: slice) -> list[StudyPoint]: ...

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        n = len(self)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(f"point {i} of a study of {n} points")
        return self.make(self.params_at(i))

    def __iter__(self) -> Iterator[StudyPoint]:
        if self.axes:
            names = tuple(self.axes)
            for combo in itertools.product(*self.axes.values()):
                yield self.make(merge(self.fixed, dict(zip(names, combo, strict=True))))
        for p in self.listed:
            yield self.make(dict(p))

    def index(self, params: Mapping[str, Any], start: int = 0, stop: int | None = None) -> int:
        """Position of the point with exactly these parameters (ValueError if none)."""
        i = self.find(params)
        if i is None or i < start or (stop is not None and i >= stop):
            raise ValueError("no point of the study has these parameters")
        return i

    def find(self, params: Mapping[str, Any]) -> int | None:
        """Position of the point with exactly these parameters, or None."""
        if self.axes and set(params) == set(self.fixed) | set(self.axes):
            i = 0
            for k, vals in self.axes.items():
                r = self._slot[k].get(_key(params[k]))
                if r is None:
                    break
                i = i * len(vals) + r
            else:
                if all(_key(params[k]) == _key(v) for k, v in self.fixed.items()
                       if k not in self.axes):
                    return i
        j = self._listed_at.get(canonical_json(params))
        return None if j is None else self.n_grid + j

    def __contains__(self, point: object) -> bool:
        return (isinstance(point, StudyPoint) and self.find(point.params) is not None
                and self.make(dict(point.params)).id == point.id)

    def column_values(self, name: str) -> Iterator[Any]:
        """Every value parameter ``name`` takes across the points (None where a point does
        not set it), each grid value once: what the plots ask of a column."""
        if self.n_grid:
            yield from self.axes.get(name, (self.fixed.get(name),))
        for p in self.listed:
            yield p.get(name)


def _key(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))
