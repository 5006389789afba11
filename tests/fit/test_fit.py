"""hdrjax.fit: recovery of known parameters, sensitivities, result codes, bounds, batches."""

import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
import pytest

import hdrjax
from hdrjax import fit as hf, targets as ht

from ..conftest import DATA, RTOL32


@pytest.fixture(scope="module")
def cornell():
    """The Cornell box (data/cornell_box.exr), box-filtered to 32 × 32 (float64 NumPy)."""
    rgb = np.asarray(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), np.float64)
    return rgb.reshape(32, 16, 32, 16, 3).mean(axis=(1, 3))


def _lognormal(seed, n=16):
    return np.exp(np.random.default_rng(seed).normal(0.0, 1.5, (n, n, 3)))


def test_recovers_tumblin_reinhard_from_reference_image(cornell, x64):
    x = jnp.asarray(cornell)
    true = hdrjax.make_operator("tumblin_reinhard", L_wa=0.6, L_white=0.7)
    start = hdrjax.make_operator("tumblin_reinhard", L_wa=1.5, L_white=1.2)
    res = hf.fit(start, x, ht.Reference(true(x)), params=("L_wa", "L_white"))
    assert bool(res.success)
    np.testing.assert_allclose(res.params["L_wa"], 0.6, rtol=1e-4)
    np.testing.assert_allclose(res.params["L_white"], 0.7, rtol=1e-4)
    assert float(res.loss) < 1e-12 and int(res.steps) > 1


def test_recovers_reinhard_from_statistics_and_jacobian_matches_fd(cornell, x64):
    x = jnp.asarray(cornell)
    target0 = ht.MeanLuminance(0.0) + ht.Percentiles((5, 95), (0.0, 0.0))
    true = hdrjax.make_operator("reinhard2002", key=0.3, L_white=2.5).measure(x)
    stats = np.asarray(target0.statistics(true(x)))
    target = ht.MeanLuminance(stats[0]) + ht.Percentiles((5, 95), stats[1:])
    start = hdrjax.make_operator("reinhard2002", key=0.1, L_white=6.0)
    res = hf.fit(start, x, target, params=("key", "L_white"))
    assert bool(res.success)
    np.testing.assert_allclose(res.params["key"], 0.3, rtol=1e-4)
    np.testing.assert_allclose(res.params["L_white"], 2.5, rtol=1e-4)
    np.testing.assert_allclose(res.statistics, stats, rtol=1e-8)
    # sensitivities: central finite differences of the statistics at the solution
    stats_at = jax.jit(
        lambda k, w: target.statistics(
            eqx.tree_at(lambda o: (o.key, o.L_white), res.operator, (k, w))(x)
        )
    )
    k, w = float(res.params["key"]), float(res.params["L_white"])
    for name, dk, dw in (("key", 1e-6 * k, 0.0), ("L_white", 0.0, 1e-6 * w)):
        h = dk + dw
        s = [
            np.asarray(stats_at(jnp.asarray(k + e * dk), jnp.asarray(w + e * dw))) for e in (1, -1)
        ]
        np.testing.assert_allclose(res.jacobian[name], (s[0] - s[1]) / (2 * h), rtol=1e-6)
    np.testing.assert_allclose(
        res.sensitivity()[:, 0], res.jacobian["key"] * 0.3 / stats, rtol=1e-4
    )


def _linear_fit(x, target=None, **kw):
    return hf.fit(
        hdrjax.make_operator("linear", L_max=5.0),
        x,
        ht.MeanLuminance(0.25) if target is None else target,
        params="L_max",
        **kw,
    )


# The float32 16 × 16 Linear fits below share one compiled solve (same static settings).


def test_converged_fit_meets_target_and_minimiser_agrees():
    x = jnp.asarray(_lognormal(2), jnp.float32)
    res = _linear_fit(x)
    assert bool(res.success) and res.result == optx.RESULTS.successful
    np.testing.assert_allclose(res.statistics, [0.25], rtol=RTOL32)
    # Linear: display = rgb / L_max, clipped per channel; ∂/∂L_max of an unclipped channel
    # value c is −c / L_max, of a clipped one 0
    L_max = float(res.params["L_max"])
    d = np.asarray(x) / L_max
    dd = np.where(d < 1, -d / L_max, 0.0) @ np.asarray(hdrjax.REC709_WEIGHTS)
    np.testing.assert_allclose(res.jacobian["L_max"], [dd.mean()], rtol=1e-3)
    bfgs = _linear_fit(x, solver=optx.BFGS(rtol=1e-6, atol=1e-8))
    assert bool(bfgs.success)
    np.testing.assert_allclose(bfgs.params["L_max"], res.params["L_max"], rtol=1e-3)


def test_non_convergence_is_a_failure_code_and_throw_raises():
    x = jnp.asarray(_lognormal(0), jnp.float32)
    res = _linear_fit(x, max_steps=2)
    assert not bool(res.success)
    assert res.result == optx.RESULTS.nonlinear_max_steps_reached
    assert np.isfinite(float(res.loss)) and float(res.loss) > 1e-6
    with pytest.raises(Exception, match="maximum number of steps"):
        jax.block_until_ready(_linear_fit(x, max_steps=2, throw=True))


def test_log_space_keeps_parameters_positive_and_bounds_hold():
    # mean display luminance 1 needs every pixel clipped, i.e. L_max below the darkest
    # pixel: a linear-space step can overshoot to L_max ≤ 0; log space stays positive.
    x = jnp.asarray(_lognormal(1), jnp.float32)
    res = _linear_fit(x, ht.MeanLuminance(1.0))
    assert bool(res.success)
    assert 0 < float(res.params["L_max"]) <= float(jnp.min(hdrjax.luminance(x)))
    lin = _linear_fit(
        x, ht.MeanLuminance(1.0), max_steps=30, log_space=False, bounds={"L_max": (0.5, 100.0)}
    )
    assert 0.5 <= float(lin.params["L_max"]) < 0.6  # from 5.0 towards the bound, never past


def test_fits_stay_in_the_declared_ranges_and_signed_parameters_are_not_logged():
    """A fit never leaves a parameter's declared valid range (drago2003's bias was fitted
    to 529 for a dark target: no operator), user bounds are narrowed to it, and a parameter
    that may be negative (an exposure in EV, default 0) is not fitted as ``ln p`` (it stayed
    at 0 and failed)."""
    x = np.random.default_rng(0).lognormal(0, 2, (32, 48, 3)).astype(np.float32)
    res = hf.fit("agx", x, ht.MeanLuminance(0.3), params="exposure")
    assert res.success
    np.testing.assert_allclose(float(res.statistics[0]), 0.3, rtol=1e-4)
    assert float(res.params["exposure"]) < 0  # darker than the default exposure
    # a mean the bias cannot reach within (0, 1): unsuccessful, and still a valid operator
    res = hf.fit("drago2003", x, ht.MeanLuminance(0.05), params="bias")
    assert not res.success
    bias = float(res.params["bias"])
    assert 0.99 < bias < 1.0
    assert np.all(np.isfinite(np.asarray(hdrjax.tonemap(x, "drago2003", bias=bias))))
    res = hf.fit("drago2003", x, ht.MeanLuminance(0.05), params="bias", bounds={"bias": (0.5, 2)})
    assert 0.99 < float(res.params["bias"]) < 1.0
    with pytest.raises(ValueError, match=r"^bounds\['bias'\]: no value within the bounds"):
        hf.fit("drago2003", x, ht.MeanLuminance(0.05), params="bias", bounds={"bias": (1, 2)})
    # a positive parameter fitted as it is (not as ln p) keeps its declared lower end 0:
    # exponential's log-average went to -1.65 for a mean it cannot reach ("success")
    res = hf.fit("exponential", x, ht.MeanLuminance(0.999), params="log_average", log_space=False)
    assert float(res.params["log_average"]) >= 0.0
    assert not res.success


def test_default_parameters_and_solver_fit_every_kind_of_operator():
    """``params=None`` fits what the operator measures as numbers (linear: ``L_max``, not
    its unset camera exposure; reinhard2002_auto: not its ``local`` flag; both raised), and
    an operator without forward-mode derivatives (chiu1993's custom VJP: every default fit
    raised a TypeError) is fitted by a minimiser with reverse-mode Jacobians."""
    x = np.random.default_rng(0).lognormal(0, 2, (16, 24, 3)).astype(np.float32)
    # the defaults, as a bound on another name lists them (the error comes before compiling)
    for name, fitted in [
        ("linear", "['L_max']"),
        ("reinhard2002_auto", "['key', 'L_white', 'log_average']"),
    ]:
        with pytest.raises(
            ValueError, match=rf"^bounds: \['q'\] are not fitted parameters {re.escape(fitted)}$"
        ):
            hf.fit(name, x, ht.MeanLuminance(0.3), bounds={"q": (0, 1)})
    assert hf.fit("linear", x, ht.MeanLuminance(0.3)).success
    chiu = hf.fit("chiu1993", x, ht.MeanLuminance(0.3), params="k")
    assert chiu.success
    np.testing.assert_allclose(float(chiu.statistics[0]), 0.3, rtol=1e-4)
    assert np.isfinite(np.asarray(chiu.jacobian["k"])).all() and float(chiu.jacobian["k"][0]) < 0


def test_fit_batch_equals_separate_fits():
    frames = jnp.asarray(np.stack([_lognormal(s) * (s + 1) for s in range(3)]), jnp.float32)
    batch = hf.fit_batch(
        hdrjax.make_operator("linear", L_max=5.0), frames, ht.MeanLuminance(0.25), params="L_max"
    )
    assert batch.success.shape == (3,) and bool(jnp.all(batch.success))
    for i in range(3):
        one = _linear_fit(frames[i])
        np.testing.assert_allclose(batch.params["L_max"][i], one.params["L_max"], rtol=RTOL32)
        np.testing.assert_allclose(batch.jacobian["L_max"][i], one.jacobian["L_max"], rtol=1e-3)
        assert int(batch.steps[i]) == int(one.steps)


def test_fit_sequence_smoothing():
    frames = jnp.asarray(np.stack([_lognormal(3) * s for s in (1.0, 1.2, 3.0)]), jnp.float32)
    op = hdrjax.make_operator("linear", L_max=5.0)
    tgt = ht.MeanLuminance(0.25)
    free = hf.fit_sequence(op, frames, tgt, smoothness=0.0, params="L_max")
    stiff = hf.fit_sequence(op, frames, tgt, smoothness=1e4, params="L_max")
    assert bool(jnp.all(free.success)) and bool(jnp.all(stiff.success))
    for i in range(3):
        one = _linear_fit(frames[i])
        np.testing.assert_allclose(free.params["L_max"][i], one.params["L_max"], rtol=1e-3)
    spread = lambda r: np.ptp(np.log(np.asarray(r.params["L_max"])))  # noqa: E731
    assert spread(stiff) < 1e-2 * spread(free)


def test_validation_errors():
    x = jnp.ones((4, 4, 3))
    tgt = ht.MeanLuminance(0.2)
    with pytest.raises(ValueError, match="valid"):
        hf.fit("linear", x, tgt, params="nope")
    with pytest.raises(ValueError, match="lo < hi"):
        hf.fit("linear", x, tgt, params="L_max", bounds={"L_max": (2.0, 1.0)})
    with pytest.raises(ValueError, match="not fitted"):
        hf.fit("linear", x, tgt, params="L_max", bounds={"ev100": (1.0, 2.0)})
    with pytest.raises(ValueError, match="target"):
        hf.fit("linear", x, 0.2, params="L_max")
    with pytest.raises(ValueError, match="fit_batch"):
        hf.fit("linear", jnp.ones((2, 4, 4, 3)), tgt, params="L_max")


def test_downscale_is_a_box_filter():
    x = jnp.arange(2 * 6 * 3, dtype=jnp.float32).reshape(2, 6, 3)
    y = hf.downscale(x, 3)
    assert y.shape == (1, 3, 3)
    np.testing.assert_allclose(y[0, 0], np.asarray(x[:, :2]).mean(axis=(0, 1)))
    assert hf.downscale(x, None) is x
    # a side shorter than the factor is averaged whole: a 1-row image keeps its row (it
    # became (0, 3, 3), an empty image the fit then failed on; issue 16.4)
    thin = hf.downscale(x[:1], 3)
    assert thin.shape == (1, 3, 3)
    np.testing.assert_allclose(thin[0, 1], np.asarray(x[0, 2:4]).mean(axis=0))


def test_exact_reference_match_is_a_success_with_finite_sensitivity():
    # loss exactly 0: the RMSE statistic's derivative must not be ∞ (it once made the fit
    # report "non-finite" at the perfect answer)
    x = np.random.default_rng(0).lognormal(0, 1, (32, 32, 3)).astype(np.float32)
    ref = np.asarray(hdrjax.tonemap(x, "linear", L_max=8.0))
    res = hf.fit(
        hdrjax.make_operator("linear", L_max=5.0),
        x,
        ht.Reference(ref),
        params="L_max",
        max_size=None,
    )
    assert bool(res.success)
    np.testing.assert_allclose(float(res.params["L_max"]), 8.0, rtol=1e-5)
    assert np.all(np.isfinite(np.asarray(res.jacobian["L_max"])))


def test_default_solver_agrees_with_minpack_on_a_numpy_model(cornell, x64):
    # the benchmark's problem (benchmarks/bench_fit.py) on the Cornell box: reinhard2002's
    # key and L_white so that mean display luminance is 0.2 and P99 0.95, from key 0.18,
    # L_white 10, in ln p; the peer is scipy's MINPACK on a NumPy model of the operator
    # (JGT 2002 Eqs. 2–4, colour scaled by L_d / L_w) and of the two statistics
    import scipy.optimize

    w = np.asarray(hdrjax.REC709_WEIGHTS)
    lbar = float(np.exp(np.mean(np.log(1e-6 + np.maximum(cornell @ w, 0)))))

    def stats(z):
        key, white = np.exp(z)
        L = cornell @ w
        Ls = key / lbar * L
        Ld = Ls / (1 + Ls) * (1 + Ls / white**2)
        disp = cornell * np.where(L > 0, Ld / np.where(L > 0, L, 1), 0)[..., None]
        Lc = np.clip(disp, 0, 1) @ w
        return np.array([Lc.mean(), np.percentile(Lc[Lc > 0], 99)])

    want = np.array([0.2, 0.95])
    sol = scipy.optimize.least_squares(
        lambda z: stats(z) - want, np.log([0.18, 10.0]), method="lm", xtol=1e-12, ftol=1e-12
    )
    assert sol.success and np.sum(sol.fun**2) < 1e-20
    start = hdrjax.make_operator("reinhard2002", key=0.18, L_white=10.0, log_average=lbar)
    res = hf.fit(
        start,
        jnp.asarray(cornell),
        ht.MeanLuminance(0.2) + ht.Percentiles(99, 0.95),
        params=("key", "L_white"),
        max_size=None,
    )
    assert bool(res.success) and float(res.loss) < 1e-20
    np.testing.assert_allclose(
        [float(res.params["key"]), float(res.params["L_white"])], np.exp(sol.x), rtol=1e-6
    )
    np.testing.assert_allclose(res.statistics, want, rtol=1e-8)


def _feeding(name):
    """``{parameter: [parameters it only serves to estimate]}`` of a registered operator."""
    out = {}
    for p, q in hdrjax.get_operator(name).only_feeds.items():
        out.setdefault(q, []).append(p)
    return out


@pytest.mark.parametrize(
    "name", [n for n in hdrjax.operator_names() if hdrjax.get_operator(n).only_feeds]
)
def test_only_feeds_parameters_do_not_change_the_output(name):
    # what the fit relies on to skip measuring (``only_feeds``, over the registry): with the
    # estimated parameter set, the values of the parameters that feed it change nothing
    x = jnp.asarray(_lognormal(5, 8), jnp.float32)
    # the shape of each measured value (lischinski2006's zone exposures are a vector)
    measured = eqx.filter_eval_shape(lambda o, v: o.measure(v), hdrjax.make_operator(name), x)
    for q, ps in _feeding(name).items():
        op = eqx.tree_at(
            lambda o, q=q: getattr(o, q),
            hdrjax.make_operator(name),
            # not the value the feeding ones would give
            jnp.full(getattr(measured, q).shape, 0.37, jnp.float32),
            is_leaf=lambda v: v is None,
        )
        want = np.asarray(op(x))
        assert len(np.unique(want)) > 10  # the output varies: its parameters matter
        for scale in (0.5, 3.0):
            fed = eqx.tree_at(
                lambda o, ps=ps: tuple(getattr(o, p) for p in ps),
                op,
                tuple(jnp.asarray(scale * (i + 1), jnp.float32) for i in range(len(ps))),
                is_leaf=lambda v: v is None,
            )
            np.testing.assert_array_equal(np.asarray(fed(x)), want, err_msg=f"{ps} -> {q}")


def test_unused_measured_parameters_are_not_measured():
    # tumblin_reinhard with L_wa and L_white given never uses L_max (it only derives
    # L_white): the fit skips measuring it (a pass over the full image) and leaves it None;
    # where a measured value matters (L_white unset; reinhard2002's log-average) it measures
    from hdrjax.fit._fit import _output_needs_unset

    x = jnp.asarray(_lognormal(4, 8), jnp.float32) * 50
    op = hdrjax.make_operator("tumblin_reinhard", L_wa=2.0, L_white=0.5)
    assert not _output_needs_unset(op)
    assert _output_needs_unset(hdrjax.make_operator("tumblin_reinhard", L_wa=2.0))
    assert _output_needs_unset(hdrjax.make_operator("reinhard2002", key=0.2, L_white=3.0))
    assert not _output_needs_unset(hdrjax.make_operator("linear", L_max=2.0))  # exposure unused
    assert _output_needs_unset(hdrjax.make_operator("linear", ev100=3.0))  # L_max from ev100
    res = hf.fit(op, x, ht.MeanLuminance(0.3), params="L_wa", max_size=None)
    assert bool(res.success) and res.operator.L_max is None
    L_max = float(np.max(np.asarray(x) @ np.asarray(hdrjax.REC709_WEIGHTS)))
    with_max = eqx.tree_at(
        lambda o: o.L_max, res.operator, jnp.asarray(L_max), is_leaf=lambda v: v is None
    )
    np.testing.assert_array_equal(np.asarray(res.operator(x)), np.asarray(with_max(x)))
    np.testing.assert_allclose(
        float(ht.MeanLuminance(0.3).statistics(with_max(x))[0]), 0.3, rtol=1e-4
    )
