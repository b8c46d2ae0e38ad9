"""Fuzz cases for every public function of pointscale: the hypothesis strategies that
tests/test_fuzz.py (a short run) and scripts/fuzz.py (the long run) both draw from.

A case is a small, printable recipe: `Case(function, arguments)`, where point sets are
`Cloud(...)` recipes and decompositions `Saved(...)` recipes (a decomposition of a fixed shape,
saved, its arrays mutated, its bytes damaged, loaded again). `repr(case)` is Python that rebuilds
it: `from fuzz_cases import *; run(<repr>)` reproduces a failure.

The contract every case is held to (`run`): the call returns a finite result, or raises
ValueError, or pointscale.Cancelled (a progress callback said stop). Any other exception, a NaN
or infinity in a result, a crash or a hang is a failure.
"""
from __future__ import annotations

import io
import os
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np
from hypothesis import strategies as st

import pointscale as ps

# ------------------------------------------------------------------------------------ point sets

KINDS = ("sphere", "bumpy", "torus", "patch", "plane", "line", "point", "cube", "sheets", "cluster_and_far")


@dataclass(frozen=True)
class Cloud:
    """A point set: `kind` of n points, times scale, plus offset; optionally with duplicated
    points, a NaN or inf, or returned with the wrong shape or dtype (`form`)."""
    kind: str
    n: int
    scale: float = 1.0
    offset: float = 0.0
    seed: int = 0
    duplicates: float = 0.0
    jitter: float = 0.0
    bad: str = ""      # "", "nan", "inf", "huge"
    form: str = ""     # "", "float32", "int", "2d", "flat", "list", "complex", "str", "empty"

    def build(self):
        rng = np.random.default_rng(self.seed)
        n = max(int(self.n), 1)
        k = self.kind
        if k == "sphere":
            p = ps.shapes.fibonacci_sphere(n)
        elif k == "bumpy":
            p = ps.shapes.bumpy_sphere(n, noise=0.002, seed=self.seed % 1000)
        elif k == "torus":
            p = ps.shapes.bumpy_torus(n)
        elif k == "patch":
            p = ps.shapes.wavy_patch(n)
        elif k == "plane":
            p = np.column_stack([rng.uniform(-1, 1, (n, 2)), np.zeros(n)])
        elif k == "line":
            p = np.outer(rng.uniform(-1, 1, n), [1.0, 2.0, -0.5])
        elif k == "point":
            p = np.tile([0.3, -0.2, 0.7], (n, 1))
        elif k == "cube":
            p = rng.uniform(-1, 1, (n, 3))
        elif k == "sheets":  # two parallel sheets closer than the sample spacing
            half = n // 2
            q = rng.uniform(-1, 1, (n, 2))
            p = np.column_stack([q, np.where(np.arange(n) < half, 0.0, 0.02)])
        elif k == "cluster_and_far":  # a tight cluster and a few points far away
            p = rng.normal(0, 1e-3, (n, 3))
            p[: max(1, n // 50)] += rng.normal(0, 1e3, (max(1, n // 50), 3))
        else:
            raise AssertionError(k)
        p = np.asarray(p, dtype=np.float64)
        n = len(p)  # the shapes may round n (a patch keeps a square grid)
        if self.jitter:
            p = p + rng.normal(0, self.jitter, p.shape)
        if self.duplicates and n > 1:
            m = int(self.duplicates * n)
            if m:
                p[rng.integers(0, n, m)] = p[rng.integers(0, n, m)]
        with np.errstate(over="ignore", invalid="ignore"):
            p = p * self.scale + self.offset
        if self.bad and n:
            i = int(rng.integers(0, n))
            p[i, int(rng.integers(0, 3))] = {"nan": np.nan, "inf": -np.inf, "huge": 1e308}[self.bad]
        return _reform(p, self.form)


def _reform(p, form):
    if form == "float32":
        with np.errstate(over="ignore"):
            return p.astype(np.float32)
    if form == "int":
        return np.clip(np.nan_to_num(p), -1e18, 1e18).astype(np.int64)
    if form == "2d":
        return p[:, :2]
    if form == "flat":
        return p.reshape(-1)
    if form == "list":
        return p.tolist()
    if form == "complex":
        return p.astype(np.complex128)
    if form == "str":
        return p[:5].astype(str)
    if form == "empty":
        return p[:0]
    return p


SCALES = [1e-320, 1e-300, 1e-200, 1e-100, 1e-60, 1e-51, 1e-49, 1e-30, 1e-8, 1e-3, 1.0, 1e3, 1e8, 1e30,
          1e49, 1e51, 1e60, 1e100, 1e149, 1e151, 1e200, 1e300]
OFFSETS = [0.0, 1.0, -1e3, 1e8, 1e16, 1e30, 1e100, 1e160, -1e300]


def clouds(min_n=1, max_n=1500, kinds=KINDS, plain=False):
    """Point-set recipes: mostly normal clouds, sometimes extreme scales, offsets, few or
    duplicated points, a NaN or inf, or the wrong form."""
    normal = st.builds(Cloud, kind=st.sampled_from(kinds), n=st.integers(max(min_n, 200), max_n),
                       seed=st.integers(0, 2**16))
    if plain:
        return normal
    extreme = st.builds(
        Cloud, kind=st.sampled_from(kinds), n=st.one_of(st.integers(min_n, 12), st.integers(min_n, max_n)),
        scale=st.one_of(st.sampled_from(SCALES), st.floats(-1e6, 1e6, allow_nan=False),
                        st.builds(lambda e: 10.0 ** e, st.integers(-310, 308))),
        offset=st.sampled_from(OFFSETS), seed=st.integers(0, 2**16),
        duplicates=st.sampled_from([0.0, 0.0, 0.1, 0.5, 1.0]),
        jitter=st.sampled_from([0.0, 0.0, 1e-12, 1e-6, 0.01]),
        bad=st.sampled_from(["", "", "", "", "nan", "inf", "huge"]),
        form=st.sampled_from([""] * 12 + ["float32", "int", "2d", "flat", "list", "complex", "str", "empty"]))
    return st.one_of(normal, normal, extreme)


# ------------------------------------------------------------------------------------ parameters

BAD_NUMBERS = [0, -1, 2**31, 2**31 - 1, 2**63, 10**20, -(2**31) - 1, float("nan"), float("inf"), -float("inf"),
               1e308, 1e-308, 0.5, 2.5, "3", "a", None, True, [1, 2], np.int64(5), np.float32(0.5)]


def ints(lo, hi, extreme=True):
    """Whole numbers in a useful range, and one time in ten anything else."""
    good = st.integers(lo, hi)
    return st.one_of([good] * 9 + [st.sampled_from(BAD_NUMBERS)]) if extreme else good


def reals(lo, hi, extreme=True):
    """Floats in a useful range, and one time in ten anything else."""
    good = st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    return st.one_of([good] * 9 + [st.sampled_from(BAD_NUMBERS)]) if extreme else good


THREADS = st.one_of([st.sampled_from([0, 1, 2, 3])] * 5 + [st.sampled_from([-1, 1024, 1025, 2**31, 2**40, 1.5,
                                                                              2.0, "2", None, True])])


@dataclass(frozen=True)
class Progress:
    """A progress callback: returns `value` (or raises) from its `after`-th call on."""
    value: object = True
    after: int = 0
    calls: list = field(default_factory=list, compare=False, hash=False, repr=False)

    def __call__(self, fraction):
        self.calls.append(fraction)
        if len(self.calls) <= self.after:
            return True
        if self.value == "raise":
            raise ValueError("the callback raised")
        return self.value


PROGRESS = st.one_of(st.none(), st.builds(Progress, value=st.sampled_from([True, False, None, 1, 0, 1.0, "yes", "",
                                                                           [1], "raise", np.bool_(False)]),
                                          after=st.integers(0, 3)),
                     st.sampled_from([3, "progress"]))

# ------------------------------------------------------------------------------------ decompositions

SOURCES = ("mls", "diffusion", "rayshoot", "encode", "small")
_SOURCE_CACHE: dict = {}


def source_decomposition(name: str) -> ps.Decomposition:
    """A valid decomposition of a fixed shape, made once per process."""
    if name not in _SOURCE_CACHE:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sphere = ps.shapes.bumpy_sphere(2000, seed=1)
            if name == "mls":
                d = ps.decompose(sphere, levels=3)
            elif name == "diffusion":
                d = ps.decompose(sphere, levels=3, smoother="diffusion")
            elif name == "rayshoot":
                d = ps.decompose_rayshoot(sphere, levels=3)
            elif name == "encode":
                d = ps.encode(sphere, ps.ellipsoid_base(sphere, n=1000))
            elif name == "small":
                d = ps.decompose(ps.shapes.wavy_patch(200), levels=2, decimation=0.2)
            else:
                raise AssertionError(name)
        _SOURCE_CACHE[name] = d
    return _SOURCE_CACHE[name]


@dataclass(frozen=True)
class Mutation:
    """One change to a saved decomposition's arrays. `how` is one of MUTATIONS; `key` the array
    (or its position among the sorted keys, when an int); `seed` picks elements and values."""
    how: str
    key: object = 0
    seed: int = 0

    def apply(self, arrays: dict) -> None:
        keys = sorted(arrays)
        key = self.key if isinstance(self.key, str) else keys[int(self.key) % len(keys)]
        rng = np.random.default_rng(self.seed)
        if self.how in ("settings", "stats"):  # garbage JSON text
            text = [b"{", b"[1, 2]", b"null", b'"x"', b"\xff\xfe", b'{"levels": "x"}', b"{}" * 3, b"",
                    b'{"a": ' * 2000 + b"1" + b"}" * 2000, b"[" + b"{}, " * 5 + b"{}]",
                    b'[{"support_points": 1e999}]'][self.seed % 11]
            arrays[self.how] = np.frombuffer(text, dtype=np.uint8).copy()
            return
        if self.how == "plausible":  # passes every check of load, but the structure is random
            try:
                _plausible(arrays, rng)
            except (IndexError, ValueError, TypeError, KeyError):
                pass  # an earlier mutation broke the arrays already: load refuses them anyway
            return
        if key not in arrays:
            arrays[key] = np.zeros(3)
            return
        a = np.array(arrays[key])
        how = self.how
        if how == "drop":
            del arrays[key]
            return
        if how == "extra":
            arrays[f"extra_{self.seed % 7}"] = rng.normal(size=5)
            return
        if how in ("trim", "extend", "trim1", "extend1"):
            axis = 1 if how.endswith("1") else 0
            if a.ndim <= axis:
                a = a.reshape(-1)
                axis = 0
            m = a.shape[axis]
            if how.startswith("trim"):
                keep = int(rng.integers(0, max(m, 1)))
                a = np.take(a, np.arange(keep), axis=axis)
            else:
                extra = int(rng.integers(1, 4))
                a = np.concatenate([a, np.take(a, np.arange(min(extra, m)) if m else [], axis=axis)]
                                   if m else [a], axis=axis) if m else np.zeros((extra,) + a.shape[1:], a.dtype)
            arrays[key] = a
            return
        if how == "retype":
            dtype = [np.float32, np.float16, np.int64, np.int8, np.uint8, np.uint32, np.bool_, np.complex128,
                     np.float64, np.int32, "U3"][self.seed % 11]
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                arrays[key] = a.astype(dtype)
            return
        if how == "scalar":
            arrays[key] = np.array(a.reshape(-1)[0] if a.size else 0)
            return
        if how == "reshape":
            arrays[key] = a.reshape(-1) if a.ndim > 1 else a.reshape(1, -1)
            return
        if how == "transpose":
            arrays[key] = np.ascontiguousarray(a.T) if a.ndim == 2 else a[None]
            return
        if a.size == 0 or a.dtype.kind not in "fiub":
            return
        flat = a.reshape(-1).copy()
        i = int(rng.integers(0, flat.size))
        if how == "value":
            values = ([np.nan, np.inf, -np.inf, 1e300, -1e300, 1e-310, 0.0, -1.0, 1e60, 1e40] if a.dtype.kind == "f"
                      else [-1, flat.max() + 1, 2**31 - 1, -(2**31), 0, flat.size])
            v = values[self.seed % len(values)]
            try:
                flat[i] = v
            except (OverflowError, ValueError):
                flat[i] = 0
        elif how == "shuffle":  # in range, but the structure is inconsistent
            rng.shuffle(flat)
        elif how == "random":
            if a.dtype.kind in "iu":
                flat = rng.integers(0, max(int(flat.max()) + 1, 1), flat.size).astype(a.dtype)
            elif a.dtype.kind == "f":
                flat = rng.normal(0, 1, flat.size)
            else:
                flat = rng.integers(0, 256, flat.size).astype(a.dtype)
        elif how == "zero":
            flat[:] = 0
        arrays[key] = flat.reshape(a.shape)


def _plausible(arrays: dict, rng) -> None:
    """Replaces one level's structure (or the normals, details or local coordinates) with random
    values in range: cluster indices, anchors still members of their clusters, positive kernel
    widths, unit normals. load accepts it; the core must still give finite points or refuse."""
    if "details" not in arrays or "labels" not in arrays or np.asarray(arrays["details"]).ndim != 2:
        return
    k, n = np.asarray(arrays["details"]).shape
    if k == 0 or f"anchors_{k - 1}" not in arrays:
        return
    l = int(rng.integers(0, k))
    c = len(arrays[f"anchors_{l}"])
    what = int(rng.integers(0, 7))
    if what == 0:
        arrays[f"neighborhoods_{l}"] = rng.integers(0, c, np.shape(arrays[f"neighborhoods_{l}"])).astype(np.int32)
    elif what == 1:
        arrays[f"frames_{l}"] = rng.integers(0, c, (c, 2)).astype(np.int32)
    elif what == 2:
        arrays[f"local_{l}"] = rng.normal(0, 10.0 ** int(rng.integers(-3, 45)), (n, 3))
    elif what == 3:
        arrays[f"kernel_{l}"] = 10.0 ** rng.uniform(-99, 99, c)
    elif what == 4:
        v = rng.normal(size=(n, 3))
        v /= np.linalg.norm(v, axis=1)[:, None]
        v[rng.random(n) < 0.3] = 0.0
        arrays["base_normals"] = v
    elif what == 5:
        arrays["details"] = rng.normal(0, 10.0 ** int(rng.integers(-3, 49)), (k, n))
    else:
        labels = np.array(arrays["labels"])
        row = rng.integers(0, c, n).astype(labels.dtype)
        row[np.asarray(arrays[f"anchors_{l}"])] = np.arange(c)
        labels[l] = row
        arrays["labels"] = labels


MUTATIONS = ("drop", "extra", "trim", "extend", "trim1", "extend1", "retype", "scalar", "reshape", "transpose",
             "value", "value", "value", "shuffle", "random", "zero", "settings", "stats", "plausible", "plausible")


@dataclass(frozen=True)
class Saved:
    """A source decomposition, saved; its arrays mutated, then its file bytes damaged
    (`damage`: "", "truncate", "flip", "garbage", "empty", "npy"), then loaded."""
    source: str = "mls"
    mutations: tuple = ()
    damage: str = ""
    seed: int = 0

    def path(self, folder: str) -> str:
        arrays = {k: np.array(v) for k, v in source_decomposition(self.source).to_dict().items()}
        for m in self.mutations:
            m.apply(arrays)
        buffer = io.BytesIO()
        if self.damage == "npy":
            np.save(buffer, arrays.get("base", np.zeros(3)))
        else:
            np.savez_compressed(buffer, **arrays) if self.seed % 2 else np.savez(buffer, **arrays)
        data = bytearray(buffer.getvalue())
        rng = np.random.default_rng(self.seed)
        if self.damage == "truncate":
            data = data[: int(rng.integers(0, len(data)))]
        elif self.damage == "flip":
            for _ in range(int(rng.integers(1, 8))):
                data[int(rng.integers(0, len(data)))] ^= 1 << int(rng.integers(0, 8))
        elif self.damage == "garbage":
            data = bytearray(rng.integers(0, 256, int(rng.integers(0, 2000)), dtype=np.uint8).tobytes())
        elif self.damage == "empty":
            data = bytearray()
        path = os.path.join(folder, "fuzz.npz")
        with open(path, "wb") as f:
            f.write(bytes(data))
        return path

    def load(self) -> ps.Decomposition:
        with tempfile.TemporaryDirectory() as folder:
            return ps.load(self.path(folder))


def saved(max_mutations=3):
    mutation = st.builds(Mutation, how=st.sampled_from(MUTATIONS),
                         key=st.one_of(st.integers(0, 40), st.sampled_from(
                             ["base", "details", "base_normals", "labels", "origin", "settings", "format_version",
                              "kernel_0", "local_0", "local_1", "anchors_0", "frames_0", "frames_1",
                              "neighborhoods_0", "neighborhoods_1", "kernel_1", "anchors_1", "stats"])),
                         seed=st.integers(0, 2**16))
    return st.builds(Saved, source=st.sampled_from(SOURCES),
                     mutations=st.lists(mutation, max_size=max_mutations).map(tuple),
                     damage=st.sampled_from([""] * 8 + ["truncate", "flip", "garbage", "empty", "npy"]),
                     seed=st.integers(0, 2**16))


# ------------------------------------------------------------------------------------ cases


@dataclass(frozen=True)
class Gains:
    """Gains for a decomposition of k bands and n points: `kind` per band / painted / wrong."""
    kind: str = "band"
    value: float = 1.0
    seed: int = 0

    def build(self, k, n):
        rng = np.random.default_rng(self.seed)
        if self.kind == "none":
            return None
        if self.kind == "band":
            return np.full(k, self.value)
        if self.kind == "painted":
            return rng.uniform(-2, 2, (k, n)) * (self.value if np.isfinite(self.value) else 1.0)
        if self.kind == "wrong":
            return np.ones(k + 1)
        if self.kind == "nan":
            g = np.ones(k)
            g[0] = np.nan
            return g
        return "gains"


GAINS = st.builds(Gains, kind=st.sampled_from(["none", "band", "band", "painted", "wrong", "nan", "str"]),
                  value=st.one_of(st.floats(-3, 3), st.sampled_from([0.0, 1e6, 1e7, -1e300, 1e300])),
                  seed=st.integers(0, 2**16))


@dataclass(frozen=True)
class Edit:
    """An edited base: the decomposition's own base moved by `amount` x `kind`."""
    kind: str = "none"     # none, same, lift, noise, scale, wrong_n, nan, far
    amount: float = 0.1
    seed: int = 0

    def build(self, base):
        rng = np.random.default_rng(self.seed)
        if self.kind == "none":
            return None
        b = base.copy()
        with np.errstate(all="ignore"):
            if self.kind == "lift":
                b[:, 2] += self.amount * np.exp(-(b[:, :2] ** 2).sum(1))
            elif self.kind == "noise":
                b += rng.normal(0, abs(self.amount), b.shape)
            elif self.kind == "scale":
                b *= self.amount
            elif self.kind == "wrong_n":
                b = b[:-1]
            elif self.kind == "nan":
                b[0, 0] = np.nan
            elif self.kind == "far":
                b[0] += 1e60
            elif self.kind == "collapse":
                b[:] = b[0]
        return b


EDITS = st.builds(Edit, kind=st.sampled_from(["none", "none", "same", "lift", "noise", "scale", "wrong_n", "nan",
                                              "far", "collapse"]),
                  amount=st.one_of(st.floats(-2, 2), st.sampled_from([0.0, 1e-30, 1e10, 1e40, -1e45])),
                  seed=st.integers(0, 2**16))


@dataclass(frozen=True)
class Case:
    """One call: `function` (a name in CALLS) with keyword arguments (recipes are built first)."""
    function: str
    args: dict

    def __repr__(self):
        return f"Case({self.function!r}, {self.args!r})"


def _build(v):
    return v.build() if isinstance(v, Cloud) else v


def _call(case: Case):
    a = {k: _build(v) for k, v in case.args.items()}
    f = case.function
    if f == "decompose":
        return ps.decompose(a.pop("points"), **a)
    if f == "decompose_rayshoot":
        return ps.decompose_rayshoot(a.pop("points"), **a)
    if f in ("reconstruct", "reconstructor", "reconstruct_levels", "blend", "levels", "rays_missed_points"):
        dec = a["saved"].load()
        out = [dec.base, dec.details]
        k, n = dec.n_bands, dec.n_points
        gains = a["gains"].build(k, n)
        base = a["edit"].build(dec.base)
        if f == "reconstruct":
            out.append(ps.reconstruct(dec, gains, base, progress=a.get("progress")))
        elif f == "reconstructor":
            solver = ps.Reconstructor(dec)
            out.append(solver.reconstruct(gains, base, progress=a.get("progress")))
            out.append(solver.reconstruct(gains, base))
        elif f == "reconstruct_levels":
            out.append(ps.reconstruct_levels(dec, gains, base))
        elif f == "blend":
            out.append(ps.blend(dec, a["t"]))
        elif f == "levels":
            out += [dec.level(a["t"]), dec.normals(a["t"])]
        else:
            out.append(ps.rays_missed_points(dec))
        return out
    if f == "project":
        onto = a.pop("onto")
        near = a.pop("near", None)
        if near is not None:
            points = np.asarray(a["points"]) if not isinstance(a["points"], list) else a["points"]
            m = len(points) if hasattr(points, "__len__") else 0
            size = len(onto) if hasattr(onto, "__len__") else 1
            near = {"labels": np.random.default_rng(0).integers(0, max(size, 1), m),
                    "range": np.full(m, size), "float": np.zeros(m) + 0.5, "short": np.zeros(max(m - 1, 0), int),
                    "negative": np.full(m, -1)}[near]
        return ps.project(a.pop("points"), onto, near=near, **a)
    if f == "project_sheets":
        return ps.project_sheets(a.pop("points"), a.pop("onto"), **a)
    if f == "decimate":
        return ps.decimate(a.pop("points"), a.pop("target"), **a)
    if f == "estimate_normals":
        return ps.estimate_normals(a.pop("points"), **a)
    if f == "encode":
        return ps.encode(a.pop("points"), a.pop("base_points"), **a)
    if f == "ellipsoid_base":
        return ps.ellipsoid_base(a.pop("points_a"), a.pop("points_b"), n=a.pop("n"))
    if f == "morph":
        alpha, beta = a.pop("alpha"), a.pop("beta")
        m = ps.morph(a.pop("points_a"), a.pop("points_b"), a.pop("base_points"), **a)
        return [m, m.evaluate(alpha, beta)]
    if f == "smooth_diffusion":
        return ps.smooth_diffusion(a.pop("points"), a.pop("iterations"), **a)
    if f == "diffusion_levels":
        return ps.diffusion_levels(a.pop("points"), a.pop("levels"), **a)
    if f == "shoot_rays":
        onto = a.pop("onto")
        origins = a.pop("origins")
        directions = a.pop("directions")
        if isinstance(directions, str):
            o = np.asarray(origins, dtype=float) if not isinstance(origins, str) else np.zeros((1, 3))
            directions = {"outward": o, "zero": np.zeros_like(o), "tiny": np.full_like(o, 1e-200),
                          "random": np.random.default_rng(1).normal(size=o.shape) if o.ndim == 2 else o}[directions]
        return ps.shoot_rays(origins, directions, onto, **a)
    if f == "coarse_base_warning":
        return ps.coarse_base_warning(a["n"], a["levels"], a["decimation"])
    raise AssertionError(f)


class Failure(AssertionError):
    """A case broke the contract: its exception or non-finite result."""


def check_finite(value, where="result"):
    """Every float in the result must be finite."""
    if isinstance(value, ps.Decomposition):
        check_finite(value.base, where + ".base")
        check_finite(value.details, where + ".details")
        return
    if isinstance(value, ps.Morph):
        for name in ("base", "normals", "detail_a", "detail_b"):
            check_finite(getattr(value, name), f"{where}.{name}")
        return
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            check_finite(v, f"{where}[{i}]")
        return
    if isinstance(value, dict):
        for k, v in value.items():
            check_finite(v, f"{where}[{k!r}]")
        return
    if isinstance(value, np.ndarray) and value.dtype.kind in "fc":
        if not np.isfinite(value).all():
            raise Failure(f"non-finite values in {where}: {int((~np.isfinite(value)).sum())} of {value.size}")


def run(case: Case):
    """Runs one case: returns "ok", "ValueError" or "Cancelled"; raises Failure otherwise."""
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            result = _call(case)
    except ps.Cancelled:
        return "Cancelled"
    except ValueError as exc:
        if "\n" in str(exc).strip():
            raise Failure(f"a ValueError of several lines: {exc!s}") from exc
        # The last guard of the package (a result that came out non-finite) is allowed, but
        # counted apart: it means the core met something the input checks did not refuse.
        return "ValueError (non-finite result)" if "is not finite" in str(exc) else "ValueError"
    except Failure:
        raise
    except Exception as exc:
        raise Failure(f"{type(exc).__name__}: {exc}") from exc
    check_finite(result)
    return "ok"


# ------------------------------------------------------------------------------------ strategies


def _kw(**strategies):
    """Keyword arguments where each optional one is sometimes left at its default."""
    required = {k: v for k, v in strategies.items() if not k.startswith("opt_")}
    optional = {k[4:]: v for k, v in strategies.items() if k.startswith("opt_")}
    return st.fixed_dictionaries(required, optional=optional)


def _params(hostile: bool):
    """The parameter strategies: hostile ones draw anything one time in ten; valid ones stay
    in each parameter's useful range."""
    I = lambda lo, hi: ints(lo, hi, extreme=hostile)
    R = lambda lo, hi: reals(lo, hi, extreme=hostile)
    return dict(
        I=I, R=R, KERNEL=R(0.3, 4.0), NEIGHBORS=I(4, 40),
        TOL=st.one_of(st.sampled_from([1e-9, 1e-7, 1e-3]), st.sampled_from(BAD_NUMBERS)) if hostile
        else st.sampled_from([1e-9, 1e-7, 1e-3]),
        MAX_IT=I(1, 60), DIFFUSION_IT=I(1, 40), LAM=R(0.05, 1.0),
        THREADS=THREADS if hostile else st.sampled_from([0, 1, 2, 3]),
        PROGRESS=PROGRESS if hostile else st.one_of(st.none(), st.builds(Progress, value=st.sampled_from([True, None]))),
        GAINS=GAINS if hostile else st.builds(Gains, kind=st.sampled_from(["none", "band", "painted"]),
                                              value=st.floats(-3, 3), seed=st.integers(0, 2**16)),
        EDITS=EDITS if hostile else st.builds(Edit, kind=st.sampled_from(["none", "same", "lift", "noise", "scale"]),
                                              amount=st.floats(-0.5, 0.5), seed=st.integers(0, 2**16)),
        SAVED=saved() if hostile else st.builds(Saved, source=st.sampled_from(SOURCES)),
    )


def case_strategies(scale: float = 1.0):
    """{function name: strategy of Case}: each function's hostile cases and valid ones, half
    and half. scale shrinks point counts (the short run uses 0.5 of the long run's)."""
    hostile = _case_strategies(scale, True)
    valid = _case_strategies(scale, False)
    return {name: st.one_of(valid[name], hostile[name]) for name in hostile}


def _case_strategies(scale: float, hostile: bool):
    n = max(int(1500 * scale), 300)
    P = _params(hostile)
    I, R, KERNEL, NEIGHBORS, TOL, MAX_IT, DIFFUSION_IT, LAM, THREADS_, PROGRESS_ = (
        P["I"], P["R"], P["KERNEL"], P["NEIGHBORS"], P["TOL"], P["MAX_IT"], P["DIFFUSION_IT"], P["LAM"],
        P["THREADS"], P["PROGRESS"])
    shapes = ("sphere", "bumpy", "torus", "patch", "cube", "sheets", "cluster_and_far")
    if hostile:
        big = clouds(1, n)
        surface = clouds(1, n, kinds=shapes)
        small = clouds(1, max(n // 3, 100))
        decompose_points = st.one_of(clouds(600, n, plain=True), big, surface)
    else:
        big = surface = clouds(200, n, kinds=shapes, plain=True)
        small = clouds(50, max(n // 3, 100), kinds=shapes, plain=True)
        decompose_points = clouds(600, n, kinds=("sphere", "bumpy", "torus", "cube"), plain=True)

    def case(name, args):
        return args.map(lambda a, name=name: Case(name, a))

    saved_args = dict(saved=P["SAVED"], gains=P["GAINS"], edit=P["EDITS"])
    return {
        "decompose": case("decompose", _kw(
            points=decompose_points, opt_levels=I(2, 4), opt_decimation=R(0.1, 0.5),
            opt_kernel=KERNEL, opt_neighbors=NEIGHBORS, opt_normals=st.sampled_from([None, None, None]),
            opt_smoother=st.sampled_from(["mls", "mls", "diffusion", "other"]),
            opt_encoding=st.sampled_from(["projection", "projection", "rayshoot", 3]),
            opt_tolerance=TOL, opt_max_iterations=MAX_IT, opt_max_variation=R(0.01, 0.2),
            opt_diffusion_iterations=st.one_of(DIFFUSION_IT, st.sampled_from([100, 2000, 100000, 10**6])),
            opt_lam=LAM, opt_taubin=st.booleans(), opt_diffusion_neighbors=I(3, 20),
            opt_threads=THREADS_, opt_progress=PROGRESS_)),
        "decompose_rayshoot": case("decompose_rayshoot", _kw(
            points=surface, opt_levels=I(2, 3), opt_decimation=R(0.15, 0.4), opt_kernel=KERNEL,
            opt_neighbors=NEIGHBORS, opt_max_iterations=MAX_IT, opt_fine_kernel=R(0.2, 2.0),
            opt_max_distance=st.one_of(st.none(), R(0.01, 10.0)),
            opt_smoother=st.sampled_from(["mls", "diffusion"]), opt_threads=THREADS_, opt_progress=PROGRESS_)),
        "reconstruct": case("reconstruct", _kw(**saved_args, opt_progress=PROGRESS_)),
        "reconstructor": case("reconstructor", _kw(**saved_args, opt_progress=PROGRESS_)),
        "reconstruct_levels": case("reconstruct_levels", _kw(**saved_args)),
        "blend": case("blend", _kw(**saved_args, t=R(0.0, 2.0))),
        "levels": case("levels", _kw(**saved_args, t=I(0, 2))),
        "rays_missed_points": case("rays_missed_points", _kw(**saved_args)),
        "project": case("project", _kw(
            points=small, onto=st.one_of(surface, big), opt_kernel=KERNEL, opt_neighbors=NEIGHBORS,
            opt_tolerance=TOL, opt_max_iterations=MAX_IT, opt_threads=THREADS_, opt_progress=PROGRESS_,
            opt_return_report=st.booleans(),
            opt_near=st.sampled_from([None, "labels", "range", "float", "short", "negative"]))),
        "project_sheets": case("project_sheets", _kw(
            points=small, onto=st.one_of(surface, big), opt_kernel=KERNEL, opt_sheet=R(0.05, 1.0),
            opt_neighbors=NEIGHBORS, opt_tolerance=TOL, opt_max_iterations=MAX_IT, opt_threads=THREADS_,
            opt_progress=PROGRESS_, opt_return_report=st.booleans())),
        "decimate": case("decimate", _kw(points=big, target=st.one_of(I(1, 500), st.sampled_from([10**7])),
                                         opt_max_variation=R(0.001, 1.0))),
        "estimate_normals": case("estimate_normals", _kw(points=big, opt_neighbors=I(3, 30),
                                                         opt_orient=st.booleans(), opt_threads=THREADS_)),
        "encode": case("encode", _kw(
            points=small, base_points=surface, opt_kernel=KERNEL, opt_neighbors=NEIGHBORS, opt_tolerance=TOL,
            opt_max_iterations=MAX_IT, opt_max_variation=R(0.01, 0.2), opt_threads=THREADS_,
            opt_progress=PROGRESS_)),
        "ellipsoid_base": case("ellipsoid_base", _kw(points_a=big, points_b=st.one_of(st.none(), small),
                                                     n=st.one_of(I(8, 3000), st.sampled_from([10**9, 7])))),
        "morph": case("morph", _kw(
            points_a=small, points_b=small, base_points=surface, opt_kernel=KERNEL, opt_neighbors=NEIGHBORS,
            opt_interpolation_neighbors=I(1, 16), opt_tolerance=TOL, opt_max_iterations=MAX_IT,
            opt_threads=THREADS_, opt_progress=PROGRESS_, alpha=R(-2, 2), beta=R(-2, 2))),
        "smooth_diffusion": case("smooth_diffusion", _kw(
            points=big, iterations=st.one_of(DIFFUSION_IT, st.sampled_from([1000, 5000, 10**5])),
            opt_lam=LAM, opt_taubin=st.booleans(),
            opt_mu=st.one_of(st.none(), R(-3.0, -0.05), st.sampled_from([-10.0, -100.0, 0.0])),
            opt_neighbors=I(3, 20), opt_threads=THREADS_, opt_progress=PROGRESS_)),
        "diffusion_levels": case("diffusion_levels", _kw(
            points=big, levels=st.one_of(I(2, 5), st.sampled_from([30, 64, 65])),
            opt_iterations=DIFFUSION_IT, opt_growth=R(1.0, 4.0), opt_lam=LAM, opt_taubin=st.booleans(),
            opt_mu=st.one_of(st.none(), R(-2.0, -0.05)), opt_neighbors=I(3, 20), opt_threads=THREADS_)),
        "shoot_rays": case("shoot_rays", _kw(
            origins=small, directions=st.one_of(st.sampled_from(["outward", "zero", "tiny", "random"]), small),
            onto=surface, opt_kernel=KERNEL, opt_neighbors=NEIGHBORS,
            opt_max_distance=st.one_of(st.none(), R(0.01, 10.0)), opt_tolerance=TOL,
            opt_max_iterations=MAX_IT, opt_threads=THREADS_)),
        "coarse_base_warning": case("coarse_base_warning", _kw(n=I(1, 10**7), levels=I(2, 10),
                                                               decimation=R(0.01, 0.99))),
    }


def all_cases(scale: float = 1.0):
    """One strategy over every function's cases."""
    return st.one_of(list(case_strategies(scale).values()))
