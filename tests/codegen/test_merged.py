"""Generated code evaluates a subexpression built twice once (``merged``), with the same values."""

import casadi as cs
import numpy as np

from armctl.codegen.library import merged


def test_a_subexpression_built_twice_is_evaluated_once_with_the_same_values() -> None:
    x = cs.SX.sym("x", 3)
    # sin(x₀)·cos(x₁) built twice, as two separate graphs
    a = cs.sin(x[0]) * cs.cos(x[1])
    b = cs.sin(x[0]) * cs.cos(x[1])
    fn = cs.Function("f", [x], [a + b * x[2], a * b], ["x"], ["s", "p"])
    m = merged(fn)
    assert m.n_instructions() < fn.n_instructions()
    assert (m.name(), m.name_in(), m.name_out()) == ("f", ["x"], ["s", "p"])
    for v in np.random.default_rng(0).normal(size=(20, 3)):
        s, p = (float(o) for o in m(v))
        w = np.sin(v[0]) * np.cos(v[1])  # the closed form
        assert s == float(fn(v)[0]) and p == float(fn(v)[1])
        np.testing.assert_allclose([s, p], [w + w * v[2], w * w], rtol=1e-15)


def test_a_function_that_is_not_an_sx_function_is_returned_as_it_is() -> None:
    x = cs.MX.sym("x")
    fn = cs.Function("g", [x], [2 * x])
    assert merged(fn) is fn
