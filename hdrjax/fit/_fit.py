"""Fit an operator's parameters to target statistics with optimistix.

Numeric contract: ``image`` is linear RGB ``(H, W, 3)`` as the operator expects it (relative
or cd/m²); the fitted parameters are in the operator's own units. The loss is
``Σ r²`` with ``r = target.residuals(operator(image_small))`` where ``image_small`` is the
image box-filtered down to at most ``max_size`` pixels on its long side (a target that takes
the source image, :class:`hdrjax.targets.TMQI`, gets ``image_small`` as ``source=``; each
frame's own in the batch and sequence fits) (64 by default:
statistics of 2048 pixels are as good a guide to the parameters as those of millions, and a
percentile near the median sorts, ~0.7 Mpixel/s on CPU; pass ``max_size=None`` to fit at
full resolution). Parameters the fit does not touch but that the operator measures
(``None``) are measured once, from the full-resolution image, before the fit, unless the
operator's output does not depend on any of them (``tumblin_reinhard``'s ``L_max`` once
``L_white`` is set): then they are not measured and stay ``None``.

Least-squares solvers see the residuals with a dense forward-mode Jacobian: each step
evaluates ``r`` and ``∂r/∂z`` together in one vmapped forward sweep (the primal and one
tangent per unknown), and the solver's repeated Jacobian products are products with that
small ``m × k`` matrix instead of replays of the per-pixel tangent computation.

Parametrisation (so the solver works on an unconstrained vector ``z``):

- positive parameters (``log_space``, the default for all): ``p = exp(z)``;
- bounds ``(lo, hi)``: ``p = lo + (hi − lo) σ(z)`` (in ``ln p`` when log-space and ``lo > 0``);
  one-sided: ``p = lo + exp(z)`` or ``p = hi − exp(z)``.

Every fit returns a :class:`FitResult` with an optimistix result code; a fit that runs out of
steps or ends non-finite is marked unsuccessful (and raises only with ``throw=True``). The
sensitivities are the Jacobian ``∂s/∂p`` of the target *statistics* with respect to the
fitted parameters at the solution (forward-mode autodiff), in the parameters' own units.
"""

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from .. import _check
from .._progress import compiled_progress, tick, wait_ready
from ..operators import make_operator, parameter_info
from ..operators._base import AbstractOperator, as_float_image
from ..targets import AbstractTarget, Combined, Scaled

_Bound = tuple[float | None, float | None]


class FitResult(eqx.Module):
    """The outcome of a fit (a pytree; batched along a leading axis by the batch fits).

    Attributes:
        operator: the operator with the fitted parameters (and the measured ones) set.
        params: fitted values by name.
        loss: ``Σ r²`` at the solution.
        statistics: the target statistics at the solution, shape ``(n,)``.
        residuals: the residual vector at the solution.
        jacobian: ``∂statistics/∂param`` by name, each of shape ``(n, *param.shape)``.
        steps: solver steps taken.
        result: the optimistix result code (``optx.RESULTS.successful`` when converged).
        names: the fitted parameter names, in order.
    """

    operator: AbstractOperator
    params: dict[str, Array]
    loss: Float[Array, ""]
    statistics: Float[Array, " n"]
    residuals: Float[Array, " m"]
    jacobian: dict[str, Array]
    steps: Int[Array, ""]
    result: optx.RESULTS
    names: tuple[str, ...] = eqx.field(static=True)

    @property
    def success(self) -> Bool[Array, "*batch"]:
        """True where the solver converged to a finite solution."""
        return self.result == optx.RESULTS.successful

    def sensitivity(self) -> Float[Array, "*batch n k"]:
        """Relative sensitivities (elasticities) ``(∂s/∂p) · p / s`` of scalar parameters,
        one column per fitted name: the % change of each statistic per % change of each
        parameter. Non-scalar parameters raise ``ValueError`` (use :attr:`jacobian`)."""
        cols = []
        for n in self.names:
            p = self.params[n]
            j = self.jacobian[n]
            if j.ndim != self.statistics.ndim:
                raise ValueError(f"sensitivity: {n} is not a scalar parameter; use .jacobian")
            cols.append(j * p[..., None] / self.statistics)
        return jnp.stack(cols, axis=-1)

    def _outcome(self) -> str:
        """``converged`` or the solver's reason (first sentence); ``k of n converged`` for a
        batch."""
        ok = np.asarray(self.success)
        if ok.ndim:
            return f"{int(ok.sum())} of {ok.size} converged"
        if ok:
            return "converged"
        # optx.RESULTS is indexed by its metaclass (an equinox Enumeration), unseen by mypy
        return optx.RESULTS[self.result].split(". ")[0].rstrip(".")  # type: ignore[misc]

    def __repr__(self) -> str:
        """``FitResult(reinhard2002: key=0.21; loss 3.2e-07, 12 steps, converged)``."""
        from .. import _repr

        if not _repr.concrete(self.loss):
            return f"FitResult({self.operator.name}: {', '.join(self.names)}; traced)"
        units = {i.name: _repr.short_unit(i.unit) for i in parameter_info(self.operator)}
        fitted = ", ".join(
            f"{n}={_repr.value(self.params[n], units.get(n, ''))}" for n in self.names
        )
        return (
            f"FitResult({self.operator.name}: {fitted}; loss {_repr.value(self.loss)}, "
            f"{_repr.value(self.steps)} steps, {self._outcome()})"
        )

    def _repr_html_(self) -> str:
        """A notebook's view: the fitted values with their units, the loss, steps and
        outcome, the statistics at the solution."""
        from .. import _repr

        if not _repr.concrete(self.loss):
            return _repr.preformatted(repr(self))
        infos = {i.name: i for i in parameter_info(self.operator)}
        rows = [
            (n, _repr.value(self.params[n]), infos[n].unit if n in infos else "")
            for n in self.names
        ]
        rows += [
            ("loss Σ r²", _repr.value(self.loss), ""),
            ("steps", _repr.value(self.steps), ""),
            ("outcome", self._outcome(), ""),
            ("statistics", _repr.value(self.statistics), ""),
            ("residuals", _repr.value(self.residuals), ""),
        ]
        title = f"FitResult: {type(self.operator).__name__} ({self.operator.name})"
        body = _repr.table(rows, ("fitted", "value", "unit"))
        return _repr.view(title, body, note=f"operator: {self.operator!r}")


# ----------------------------------------------------------------------------- helpers


def downscale(image: Float[Array, "H W 3"], max_size: int | None) -> Float[Array, "h w 3"]:
    """Box-filter ``image`` by the smallest integer factor that makes its long side at most
    ``max_size`` (cropping the remainder rows/columns); ``None`` keeps it as is. A side
    shorter than the factor is averaged whole (a 1-row panorama stays 1 row, not 0)."""
    if max_size is None:
        return image
    h, w = image.shape[-3], image.shape[-2]
    _check.nonempty(image.shape, "image")
    f = -(-max(h, w) // int(max_size))
    if f <= 1:
        return image
    fy, fx = min(f, h), min(f, w)
    hh, ww = h // fy, w // fx
    batch = image.shape[:-3]
    x = image[..., : hh * fy, : ww * fx, :]
    # rows first (contiguous, vectorised adds), then columns of the f-times smaller result;
    # the barrier stops XLA fusing both into one strided reduction (~10x slower on CPU)
    x = jnp.sum(x.reshape(*batch, hh, fy, ww * fx * 3), axis=-2)
    x = jax.lax.optimization_barrier(x)
    return jnp.sum(x.reshape(*batch, hh, ww, fx, 3), axis=-2) / (fy * fx)


def _to_free(p: Array, bound: _Bound, log: bool) -> Array:
    lo, hi = bound
    tiny = jnp.finfo(p.dtype).tiny
    if lo is not None and hi is not None:
        if log and lo > 0:
            u = (jnp.log(p) - jnp.log(lo)) / (jnp.log(hi) - jnp.log(lo))
        else:
            u = (p - lo) / (hi - lo)
        eps = 1e-4  # start strictly inside, where the sigmoid still has a gradient
        u = jnp.clip(u, eps, 1 - eps)
        return jnp.log(u) - jnp.log1p(-u)
    if lo is not None:
        return jnp.log(jnp.maximum(p - lo, tiny))
    if hi is not None:
        return jnp.log(jnp.maximum(hi - p, tiny))
    return jnp.log(p) if log else p


def _from_free(z: Array, bound: _Bound, log: bool) -> Array:
    lo, hi = bound
    if lo is not None and hi is not None:
        s = jax.nn.sigmoid(z)
        if log and lo > 0:
            return jnp.exp(jnp.log(lo) + (jnp.log(hi) - jnp.log(lo)) * s)
        return lo + (hi - lo) * s
    if lo is not None:
        return lo + jnp.exp(z)
    if hi is not None:
        return hi - jnp.exp(z)
    return jnp.exp(z) if log else z


class _Problem(eqx.Module):
    """Static description of a fit: which fields, how they are parametrised."""

    names: tuple[str, ...] = eqx.field(static=True)
    bounds: tuple[_Bound, ...] = eqx.field(static=True)
    log: tuple[bool, ...] = eqx.field(static=True)
    measure: bool = eqx.field(static=True, default=True)  # False: see _output_needs_unset

    def to_free(self, op: AbstractOperator) -> dict[str, Array]:
        return {
            n: _to_free(jnp.asarray(getattr(op, n)), b, lg)
            for n, b, lg in zip(self.names, self.bounds, self.log, strict=True)
        }

    def from_free(self, z: dict[str, Array]) -> dict[str, Array]:
        cfg = zip(self.names, self.bounds, self.log, strict=True)
        return {n: _from_free(z[n], b, lg) for n, b, lg in cfg}

    def with_params(self, op: AbstractOperator, p: dict[str, Array]) -> AbstractOperator:
        return eqx.tree_at(
            lambda o: tuple(getattr(o, n) for n in self.names),
            op,
            tuple(p[n] for n in self.names),
            is_leaf=lambda x: x is None,
        )


def _finish(
    prob: _Problem,
    op: AbstractOperator,
    small: Array,
    target: AbstractTarget,
    z: dict[str, Array],
    result: Any,
    steps: Array,
) -> FitResult:
    p = prob.from_free(z)
    fitted = prob.with_params(op, p)
    r = target.residuals_for(fitted(small), small)
    stats, jac = _stats_and_jacobian(
        lambda q: target.statistics_for(prob.with_params(op, q)(small), small),
        p,
        type(op).forward_mode,
    )
    loss = jnp.sum(r * r)
    finite = jnp.isfinite(loss) & jnp.all(jnp.isfinite(stats))
    for v in jax.tree_util.tree_leaves((p, jac)):
        finite = finite & jnp.all(jnp.isfinite(v))
    result = optx.RESULTS.where(finite, result, optx.RESULTS.nonfinite)
    return FitResult(fitted, p, loss, stats, r, jac, steps, result, prob.names)


_UNROLL = 4  # unknowns up to which the Jacobian's JVPs are unrolled (compile time grows)


def _stats_and_jacobian(fn: Callable[[Any], Array], p: dict[str, Array], forward: bool = True):
    """``fn(p)`` and ``∂fn/∂p`` by name (each ``(n, *p[name].shape)``), as ``jax.jacfwd``
    but with the JVPs unrolled for up to ``_UNROLL`` unknowns (see :func:`_dense_jvp`);
    ``forward=False``: ``jax.jacrev`` (``n`` is a target's few statistics)."""
    if not forward:
        return fn(p), jax.jacrev(fn)(p)
    flat, unravel = ravel_pytree(p)
    k = flat.shape[0]
    if k > _UNROLL:
        return fn(p), jax.jacfwd(fn)(p)
    basis = jnp.eye(k, dtype=flat.dtype)
    cols = [jax.jvp(lambda v: fn(unravel(v)), (flat,), (basis[i],)) for i in range(k)]
    jac = jnp.stack([c[1] for c in cols], axis=-1)  # (n, k)
    return cols[0][0], jax.vmap(unravel)(jac)


def _dense_jvp(fn: Callable[[Any], Array]) -> Callable[[Any], Array]:
    """``fn`` with a JVP that forms the whole Jacobian ``J = ∂r/∂z`` in one forward pass
    (the primal and one tangent per unknown, vmapped: ~``1 + k`` residual evaluations that
    XLA fuses into one sweep over the image) and keeps only that small ``m × k`` matrix.

    optimistix's Gauss–Newton solvers ``jax.linearize`` the residuals and then apply the
    linear map several times a step (materialising ``J``, the trust region's predicted
    reduction); on the image that replays the stored per-pixel tangent computation each
    time, here it is a ``k``-term matrix product. Reverse mode transposes that product.
    """

    def value_and_jac(z):
        flat, unravel = ravel_pytree(z)
        k = flat.shape[0]
        basis = jnp.eye(k, dtype=flat.dtype)

        def jvp(t):
            return jax.jvp(lambda v: fn(unravel(v)), (flat,), (t,))

        if k <= _UNROLL:
            # one JVP per unknown, unrolled: XLA shares the primal and fuses each tangent
            # into plain per-pixel loops; the vmapped form (below) was 2x slower at 0.5 Mpixel
            cols = [jvp(basis[i]) for i in range(k)]
            return cols[0][0], jnp.stack([c[1] for c in cols], axis=-1)
        r, jt = jax.vmap(jvp, out_axes=(None, 0))(basis)
        return r, jt.T

    @jax.custom_jvp
    def dense(z):
        return fn(z)

    @dense.defjvp
    def _(primals, tangents):
        (z,), (dz,) = primals, tangents
        r, jac = value_and_jac(z)
        return r, jac @ ravel_pytree(dz)[0].astype(jac.dtype)

    return dense


def _solve_one(prob, op, image, target, solver, max_steps, max_size, ticks=False):
    op = op.measure(image) if prob.measure else op
    small = downscale(image, max_size)

    def residuals(z):
        return target.residuals_for(prob.with_params(op, prob.from_free(z))(small), small)

    # least-squares solvers linearise; a minimiser (BFGS) takes one gradient (reverse mode)
    dense = _dense_jvp(residuals) if isinstance(solver, optx.AbstractLeastSquaresSolver) else None

    def fn(z, args):
        if ticks:  # the solver evaluates the residuals once per step
            tick(jnp.zeros(()))
        return dense(z) if dense is not None else residuals(z)

    sol = optx.least_squares(fn, solver, prob.to_free(op), max_steps=max_steps, throw=False)
    return _finish(prob, op, small, target, sol.value, sol.result, sol.stats["num_steps"])


def _throw(res: FitResult) -> FitResult:
    return res.result.error_if(res, res.result != optx.RESULTS.successful)


@eqx.filter_jit
def _fit_jit(prob, op, image, target, solver, max_steps, max_size, throw, ticks=False):
    res = _solve_one(prob, op, image, target, solver, max_steps, max_size, ticks)
    return _throw(res) if throw else res


@eqx.filter_jit
def _fit_batch_jit(
    prob,
    op,
    frames,
    target,
    solver,
    max_steps,
    max_size,
    throw,
    batch_target,
    vectorize,
    ticks=False,
):
    def one(image, tgt):
        res = _solve_one(prob, op, image, tgt, solver, max_steps, max_size)
        if ticks:  # one frame done (its result is ready)
            tick(res.steps)
        return res

    if vectorize:
        res = jax.vmap(one, in_axes=(0, 0 if batch_target else None))(frames, target)
    elif batch_target:
        res = jax.lax.map(lambda a: one(*a), (frames, target))
    else:
        res = jax.lax.map(lambda image: one(image, target), frames)
    return _throw(res) if throw else res


@eqx.filter_jit
def _fit_sequence_jit(
    prob, op, frames, target, solver, max_steps, max_size, throw, smoothness, ticks=False
):
    ops = jax.vmap(op.measure)(frames)
    smalls = jax.vmap(lambda x: downscale(x, max_size))(frames)

    def frame_residuals(o, small, z):
        return target.residuals_for(prob.with_params(o, prob.from_free(z))(small), small)

    def fn(z, args):
        if ticks:  # the solver evaluates the residuals once per step
            tick(jnp.zeros(()))
        r = jax.vmap(frame_residuals)(ops, smalls, z).reshape(-1)
        w = jnp.sqrt(jnp.asarray(smoothness, r.dtype))
        d = [w * (v[1:] - v[:-1]).reshape(-1) for v in jax.tree_util.tree_leaves(z)]
        return jnp.concatenate([r, *d])

    z0 = jax.vmap(prob.to_free)(ops)
    sol = optx.least_squares(fn, solver, z0, max_steps=max_steps, throw=False)
    steps = sol.stats["num_steps"]
    n = frames.shape[0]
    res = jax.vmap(lambda o, s, z: _finish(prob, o, s, target, z, sol.result, steps))(
        ops, smalls, sol.value
    )
    res = eqx.tree_at(lambda r: r.steps, res, jnp.broadcast_to(steps, (n,)))
    return _throw(res) if throw else res


# optimistix's LevenbergMarquardt divides the damping λ by 3.5 only after a step whose
# actual/predicted reduction ρ is ≥ 0.99 (Gould et al.'s constants); 0.75 is the classical
# threshold (Moré 1978; Nocedal & Wright, Alg. 4.1). Same start (λ = 1 in z units), same
# rejection rule (ρ < 0.01, λ × 4), same termination. On 180 fits (5 shipped images × 2
# targets × 2 operators × 9 starts, float32, 32×48) it took 18.7 steps on average instead
# of 28.2, reached the target (loss < 1e-10) in 76 cases instead of 62, ended with a lower
# loss in 21 cases and a higher one in 4 (targets neither reached), and ran out of steps in
# none (0.99: 1). A damping scaled to JᵀJ at the start (λ₀ = τ·max diag JᵀJ, τ = 0.01)
# halves the benchmark's steps but jumps into saturated regions (no gradient) more often.
_HIGH_CUTOFF = 0.75


# A target that maximises a metric (residual weight · (1 − m), hdrjax.targets.TMQI) has a
# loss with a positive minimum, around which float32 rounding makes the loss flat: there
# a short step changes Σ r² by 0 or by rounding noise, the default rule (accept when the
# actual reduction is ≥ 1% of the predicted one) rejects it, the damping grows and the fit
# runs out of steps at the optimum. Accepting every step that does not increase the loss
# (low cutoff 0, Nocedal & Wright's η = 0 in Alg. 4.1) lets the step-size test end it: on
# drago2003's bias × TMQI, 2 images × 6 starts, 12 of 12 fits converged in 13–27 steps
# (6 of 12 with the 1% rule).
_MAXIMISE_LOW_CUTOFF = 0.0


def _maximises(target: AbstractTarget) -> bool:
    """Whether ``target`` (or a part of it) maximises a metric (its ``maximises``)."""
    if isinstance(target, Combined):
        return any(_maximises(t) for t in target.targets)
    if isinstance(target, Scaled):
        return _maximises(target.target)
    return type(target).maximises


@functools.lru_cache(maxsize=32)
def _default_solver(rtol: float, atol: float, maximise: bool = False) -> optx.LevenbergMarquardt:
    # built once per tolerance pair: the constructor's checks cost ~0.3 ms a call
    solver: optx.LevenbergMarquardt = optx.LevenbergMarquardt(rtol=rtol, atol=atol)
    low = {"low_cutoff": _MAXIMISE_LOW_CUTOFF} if maximise else {}
    search: optx.ClassicalTrustRegion = optx.ClassicalTrustRegion(high_cutoff=_HIGH_CUTOFF, **low)
    return eqx.tree_at(lambda s: s.search, solver, search)


def _output_needs_unset(op: AbstractOperator) -> bool:
    """Whether ``op``'s output depends on any of its unset parameters once they are set.

    False when every unset parameter only serves to estimate another one that is set (the
    operator's :attr:`~hdrjax.operators.AbstractOperator.only_feeds`), e.g. for
    ``tumblin_reinhard`` with ``L_wa`` and ``L_white`` given: its ``L_max`` only derives
    ``L_white``. Then the fit need not measure them (a pass over the full-resolution
    image; they stay ``None`` in the result, the output is the same). An operator that
    declares nothing is measured."""
    return bool(op.unset_needed())


# built once per configuration: an equinox Module's construction costs ~0.05 ms a call
_problem = functools.lru_cache(maxsize=256)(
    lambda names, bounds, log, measure: _Problem(names, bounds, log, measure)
)


def _positive(declared: tuple[float, float] | None) -> bool:
    """Whether a parameter of this declared range is positive (``None``: undeclared, taken
    as positive, as every operator parameter was before ranges were declared)."""
    return declared is None or declared[0] >= 0


def _within(
    declared: tuple[float, float] | None,
    lo: float | None,
    hi: float | None,
    name: str,
    op: str,
    in_log: bool,
) -> _Bound:
    """The bounds ``(lo, hi)`` narrowed to the parameter's declared valid range, so that a
    fit never leaves it (a fitted drago2003 ``bias`` above 1 is no operator); an infinite
    end is no bound, and a lower end of 0 is none only where the parameter is fitted as
    ``ln p`` (``in_log``: positive already) and its range has no upper end."""
    if declared is None:
        return lo, hi
    d_lo, d_hi = (float(v) for v in declared)
    if math.isfinite(d_lo) and d_lo != 0.0:
        lo = d_lo if lo is None else max(lo, d_lo)
    elif d_lo == 0.0 and (math.isfinite(d_hi) or not in_log):
        lo = 0.0 if lo is None else max(lo, 0.0)  # (0, hi), or a positive p fitted as p
    if math.isfinite(d_hi):
        hi = d_hi if hi is None else min(hi, d_hi)
    if lo is not None and hi is not None and not lo < hi:
        raise ValueError(
            f"bounds[{name!r}]: no value within the bounds is in {op}'s valid range {declared}"
        )
    return lo, hi


def _measured(op: AbstractOperator, frame: Array) -> tuple[str, ...]:
    """The unset parameters that :meth:`~AbstractOperator.measure` sets to numbers for an
    image like ``frame`` (traced, not run): not the alternatives it leaves unset (linear's
    camera exposure when it measures ``L_max``), not its flags and node indices."""
    measured = eqx.filter_eval_shape(lambda o, x: o.measure(x), op, frame)
    return tuple(
        n
        for n in op.unset()
        if isinstance(v := getattr(measured, n), jax.ShapeDtypeStruct)
        and jnp.issubdtype(v.dtype, jnp.inexact)
    )


def _setup(
    operator: AbstractOperator | str,
    frame: Array,
    target: AbstractTarget,
    params: Sequence[str] | str | None,
    solver: Any,
    bounds: Mapping[str, _Bound] | None,
    log_space: bool | Sequence[str],
    rtol: float | None,
    atol: float | None,
) -> tuple[_Problem, AbstractOperator, Any]:
    op = make_operator(operator) if isinstance(operator, str) else operator
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"operator: expected an operator or a registered name, got {op!r}")
    if not isinstance(target, AbstractTarget):
        raise ValueError(f"target: expected an hdrjax.targets target, got {target!r}")
    if isinstance(params, str):
        params = (params,)
    names = tuple(params) if params is not None else _measured(op, frame)
    fields = {f.name for f in dataclasses.fields(op) if not f.metadata.get("static", False)}
    if not names:
        raise ValueError(
            f"params: expected names of parameters to fit from {sorted(fields)}, got none"
            f" (every parameter of {op.name} is set, so none is fitted by default)"
        )
    bad = [n for n in names if n not in fields]
    if bad or len(set(names)) != len(names):
        raise ValueError(
            f"params: {bad or list(names)} are not distinct parameters of {op.name}; "
            f"valid: {', '.join(sorted(fields))}"
        )
    bounds = dict(bounds or {})
    extra = sorted(set(bounds) - set(names))
    if extra:
        raise ValueError(f"bounds: {extra} are not fitted parameters {list(names)}")
    declared = {i.name: i.range for i in parameter_info(op)}
    if isinstance(log_space, bool):
        # ``True``: every parameter that is positive (declared range from 0 up, or none)
        log = tuple(log_space and _positive(declared.get(n)) for n in names)
    else:
        unknown = sorted(set(log_space) - set(names))
        if unknown:
            raise ValueError(f"log_space: {unknown} are not fitted parameters {list(names)}")
        log = tuple(n in log_space for n in names)
    bnds: list[_Bound] = []
    for n, lg in zip(names, log, strict=True):
        lo, hi = bounds.get(n, (None, None))
        lo = None if lo is None else float(lo)
        hi = None if hi is None else float(hi)
        if lo is not None and hi is not None and not lo < hi:
            raise ValueError(f"bounds[{n!r}]: expected lo < hi, got ({lo}, {hi})")
        lo, hi = _within(declared.get(n), lo, hi, n, op.name, lg)
        if lg and ((lo is not None and lo < 0) or (hi is not None and hi <= 0)):
            raise ValueError(f"bounds[{n!r}]: ({lo}, {hi}) not positive; {n} is in log space")
        bnds.append((lo, hi))
    if solver is None:
        x64 = jnp.result_type(float) == jnp.float64
        rtol = rtol if rtol is not None else (1e-10 if x64 else 1e-5)
        atol = atol if atol is not None else (1e-10 if x64 else 1e-6)
        if type(op).forward_mode:
            solver = _default_solver(float(rtol), float(atol), _maximises(target))
        else:  # no Jacobian-vector products: a minimiser, one reverse-mode gradient a step
            solver = optx.BFGS(rtol=float(rtol), atol=float(atol))
    elif rtol is not None or atol is not None:
        raise ValueError("rtol/atol: set them on the solver you pass")
    return _problem(names, tuple(bnds), log, _output_needs_unset(op)), op, solver


_ARGS_DOC = """
    Args:
        operator: an operator instance (its set parameters are the starting point; ``None``
            ones are measured from the image) or a registered name.
        {image}
        target: an :mod:`hdrjax.targets` target (combine several with ``+``).
        params: names of the array fields to fit (default: the unset ones the operator
            measures as numbers, e.g. ``("key", "L_white", "log_average")`` for
            ``Reinhard2002()``, ``("L_max",)`` for ``Linear()``; not flags such as
            reinhard2002_auto's ``local``).
        solver: any optimistix least-squares solver or minimiser (e.g. ``optx.BFGS``);
            default ``optx.LevenbergMarquardt`` with ``rtol``/``atol`` (damping ``λ = 1``
            at the start, in ``z`` units, divided by 3.5 after each step whose actual
            reduction of ``Σ r²`` is ≥ 0.75 of the predicted one (optimistix: 0.99), ×4
            after a rejected step: it starts cautiously, which keeps it out of flat regions
            a full Gauss–Newton step can jump into, e.g. ``L_white → ∞``). With a target
            that maximises a metric (``TMQI``, ``Naturalness``, ``PUSSIM``) it accepts every
            step that does not increase ``Σ r²`` (else only those that reduce it by ≥ 1% of
            the prediction), so that rounding noise near the optimum does not stall it.
        bounds: ``{{name: (lo, hi)}}``, either side ``None`` for one-sided bounds; always
            narrowed to the parameter's declared valid range (``hdrjax operators NAME``),
            so a fitted operator is a valid one (drago2003's ``bias`` stays in (0, 1)).
        log_space: optimise these (``True``: all positive ones: declared range from 0
            up) parameters as ``ln p``; they stay > 0. Parameters that may be negative
            (an ``exposure`` in EV) are fitted as they are.
        max_steps: solver step limit; running out is a failure code, not an answer.
        rtol, atol: tolerances of the default solver (1e-5/1e-6 in float32, 1e-10 in float64):
            it stops after an accepted step with ``max|Δz| < atol + rtol·max|z|`` and
            ``max|Δr| < atol + rtol·max|r|`` (``z`` the free parameters, ``ln p`` in log
            space; ``r`` the residuals).
        max_size: fit on the image box-filtered to this long side (``None``: full size).
        throw: raise (``EquinoxRuntimeError``) when the fit fails instead of returning the
            failure code.
"""


def _watched(jitted: Callable, args: tuple, progress: bool, image: Any, **bar: Any) -> Any:
    """``jitted(*args, ticks)`` with :func:`~hdrjax._progress.compiled_progress`'s bar
    (``bar``: its total, unit and description) where a person watches and ``image`` is
    not traced by an enclosing ``jit``."""
    show = progress and not isinstance(image, jax.core.Tracer)
    with compiled_progress(show, **bar) as ticks:
        res = jitted(*args, ticks)
        if ticks:
            wait_ready(res)
    return res


def fit(
    operator: AbstractOperator | str,
    image: Float[ArrayLike, "H W 3"],
    target: AbstractTarget,
    *,
    params: Sequence[str] | str | None = None,
    solver: Any = None,
    bounds: Mapping[str, _Bound] | None = None,
    log_space: bool | Sequence[str] = True,
    max_steps: int = 100,
    rtol: float | None = None,
    atol: float | None = None,
    max_size: int | None = 64,
    throw: bool = False,
    progress: bool = True,
) -> FitResult:
    """Fit operator parameters so the tone-mapped image meets ``target`` (jit-compiled).

    Where a person watches (a terminal or a Jupyter notebook; never in a pipe, a log or
    inside an enclosing ``jit``) and ``progress`` is true, a counter shows the solver's
    steps as they happen (its evaluations of the residuals: one per step for the default
    solver), for fits that last over a second; the call then returns when the fit is
    done.

    Returns:
        A :class:`FitResult`; check ``result.success`` (or pass ``throw=True``).

    Raises:
        ValueError: unknown parameter names, bad bounds, or a malformed image.

    >>> import jax.numpy as jnp, hdrjax.fit as hf, hdrjax.targets as ht
    >>> img = jnp.exp(jnp.linspace(-3.0, 3.0, 48)).reshape(4, 4, 3)
    >>> res = hf.fit("reinhard2002", img, ht.MeanLuminance(0.3), params="key")
    >>> bool(res.success), round(float(res.statistics[0]), 4)
    (True, 0.3)
    """
    image = as_float_image(image, "image")
    if image.ndim != 3:
        raise ValueError(f"image: expected (H, W, 3), got {image.shape}; use fit_batch")
    prob, op, solver = _setup(
        operator, image, target, params, solver, bounds, log_space, rtol, atol
    )
    args = (prob, op, image, target, solver, int(max_steps), max_size, bool(throw))
    return _watched(_fit_jit, args, progress, image, unit="step", desc=f"fit {op.name}")


fit.__doc__ = fit.__doc__.replace(  # type: ignore[union-attr]
    "\n    Returns:", _ARGS_DOC.format(image="image: linear RGB ``(H, W, 3)``.") + "\n    Returns:"
)


def fit_batch(
    operator: AbstractOperator | str,
    frames: Float[ArrayLike, "T H W 3"],
    target: AbstractTarget,
    *,
    params: Sequence[str] | str | None = None,
    solver: Any = None,
    bounds: Mapping[str, _Bound] | None = None,
    log_space: bool | Sequence[str] = True,
    max_steps: int = 100,
    rtol: float | None = None,
    atol: float | None = None,
    max_size: int | None = 64,
    throw: bool = False,
    batch_target: bool = False,
    vectorize: bool | None = None,
    progress: bool = True,
) -> FitResult:
    """One independent fit per frame, in one compiled call.

    The result's fields carry a leading frame axis (``result.success`` is ``(T,)``); each
    frame's fit equals :func:`fit` on that frame. ``vectorize=True`` vmaps the solve: the
    batched solve runs until the slowest frame converges (converged frames stay put) and the
    solver's branches are evaluated on both sides, which suits GPUs; ``False`` solves the
    frames one after another inside the compiled call (``jax.lax.map``), which on CPU is
    ~2× faster per frame than the vmapped solve and ~1.7× faster than calling :func:`fit`
    per frame (benchmarks/bench_fit.py). ``None`` (default): vmap except on CPU.

    Where a person watches and ``progress`` is true, a bar counts the frames as their fits
    end (as :func:`fit`'s counter: never in a pipe, a log or inside an enclosing ``jit``).

    Returns:
        A batched :class:`FitResult`.
    """
    frames = as_float_image(frames, "frames")
    if frames.ndim != 4:
        raise ValueError(f"frames: expected (T, H, W, 3), got {frames.shape}")
    prob, op, solver = _setup(
        operator, frames[0], target, params, solver, bounds, log_space, rtol, atol
    )
    if vectorize is None:
        vectorize = jax.default_backend() != "cpu"
    args = (prob, op, frames, target, solver, int(max_steps), max_size, bool(throw))
    args += (bool(batch_target), bool(vectorize))
    desc = f"fit_batch {op.name}"
    return _watched(
        _fit_batch_jit, args, progress, frames, total=frames.shape[0], unit="frame", desc=desc
    )


fit_batch.__doc__ = fit_batch.__doc__.replace(  # type: ignore[union-attr]
    "\n    Returns:",
    _ARGS_DOC.format(image="frames: linear RGB ``(T, H, W, 3)``.")
    + "        batch_target: the target's arrays have a leading frame axis (e.g. one\n"
    "            :class:`~hdrjax.targets.Reference` per frame).\n"
    "        vectorize: vmap the frames' solves (``True``) or map them sequentially inside the\n"
    "            compiled call (``False``); ``None``: vmap except on CPU.\n" + "\n    Returns:",
)


def fit_sequence(
    operator: AbstractOperator | str,
    frames: Float[ArrayLike, "T H W 3"],
    target: AbstractTarget,
    *,
    smoothness: float = 1.0,
    params: Sequence[str] | str | None = None,
    solver: Any = None,
    bounds: Mapping[str, _Bound] | None = None,
    log_space: bool | Sequence[str] = True,
    max_steps: int = 100,
    rtol: float | None = None,
    atol: float | None = None,
    max_size: int | None = 64,
    throw: bool = False,
    progress: bool = True,
) -> FitResult:
    """Fit a video: every frame's parameters at once, with a penalty on their changes.

    Minimises ``Σ_t Σ r_t² + smoothness · Σ_t ‖z_{t+1} − z_t‖²`` where ``z`` are the
    unconstrained parameters (``ln p`` for log-space ones, so the penalty is on relative
    changes). ``smoothness=0`` gives the independent per-frame fits; large values give one
    shared parameter set. One solve over ``T × k`` unknowns (a dense ``(T·m) × (T·k)``
    Jacobian), meant for clips of up to a few hundred frames. Where a person watches and
    ``progress`` is true, a counter shows the joint solve's steps (as :func:`fit`'s).

    Returns:
        A batched :class:`FitResult`; ``loss`` is each frame's target loss (without the
        penalty); ``steps`` and ``result`` are the joint solve's, repeated per frame.
    """
    frames = as_float_image(frames, "frames")
    if frames.ndim != 4:
        raise ValueError(f"frames: expected (T, H, W, 3), got {frames.shape}")
    prob, op, solver = _setup(
        operator, frames[0], target, params, solver, bounds, log_space, rtol, atol
    )
    if not float(smoothness) >= 0:
        raise ValueError(f"smoothness: expected >= 0, got {smoothness}")
    args = (prob, op, frames, target, solver, int(max_steps), max_size, bool(throw))
    args += (jnp.asarray(smoothness),)
    desc = f"fit_sequence {op.name}"
    return _watched(_fit_sequence_jit, args, progress, frames, unit="step", desc=desc)


fit_sequence.__doc__ = fit_sequence.__doc__.replace(  # type: ignore[union-attr]
    "\n    Returns:",
    _ARGS_DOC.format(image="frames: linear RGB ``(T, H, W, 3)``, in time order.")
    + "        smoothness: weight of the frame-to-frame penalty (≥ 0).\n"
    + "\n    Returns:",
)


__all__ = ["FitResult", "downscale", "fit", "fit_batch", "fit_sequence"]
