"""The effect derivations (tip mass, tilt) against classical results, and the generated families
against each other and the composed lever (set-back, ``pfmdyn.composed``)."""
from __future__ import annotations

import numpy as np
import sympy as sp

from pfmdyn.derivations.beam import H, L, beta, k, k1, k2
from pfmdyn.derivations.tip_mass import mu, solve as solve_tip_mass
from pfmdyn import composed
from pfmdyn.generated import elastic_contact, tilt, tip_mass

B = np.array([0.7, 1.9, 4.0, 7.5, 12.0])
ARGS = (2.4, 120.0, 100.0, 1e-5, 223e-6)


def test_tip_mass_free_frequency_equation():
    """k1 = k2 = 0: beta**6 (1 + cos cosh + mu beta (cos sinh - sin cosh)) up to a constant."""
    den = solve_tip_mass().denominator.subs({k1: 0, k2: 0, k: 2, L: 3, H: 1})
    classical = (1 + sp.cos(beta) * sp.cosh(beta)
                 + mu * beta * (sp.cos(beta) * sp.sinh(beta) - sp.sin(beta) * sp.cosh(beta)))
    ratio = sp.lambdify((beta, mu), den / (beta**6 * classical), "mpmath")
    values = {complex(ratio(b, m)) for b in (0.9, 2.3, 5.1) for m in (sp.Rational(1, 5), 2)}
    reference = values.pop()
    assert all(abs(v / reference - 1) < 1e-12 for v in values)


def test_generated_families_agree():
    e = np.array(elastic_contact.slope(B, *ARGS))
    np.testing.assert_allclose(np.array(tip_mass.slope(B, *ARGS, 0.0)), e, rtol=1e-10)
    np.testing.assert_allclose(np.array(tilt.slope(B, 2.4, 120.0, 100.0, 0.0, 1e-5, 223e-6)), e, rtol=1e-10)
    tilted = composed.Parameters(2.4, 120.0, 100.0, 30.0, 1e-5, 223e-6, 0.0, 1.0, 0.0)
    composite = composed.at_end.slope(B, tilted._replace(mu=0.3))
    separate = tip_mass.slope(B, *ARGS, 0.3)
    assert np.allclose(np.array(tilt.slope(B, 2.4, 120.0, 100.0, 30.0, 1e-5, 223e-6)),
                       np.array(composed.at_end.slope(B, tilted)),
                       rtol=1e-10)
    assert not np.allclose(np.array(composite), np.array(separate))   # tilt matters
    np.testing.assert_allclose(
        np.array(composed.at_end.slope(B, tilted._replace(kvl=0.0, mu=0.3))),
        np.array(separate), rtol=1e-10)


def test_setback_numerics_are_finite_at_large_beta():
    with np.errstate(all="raise", under="ignore"):
        out = composed.at_end.slope(np.array([50.0, 400.0, 900.0]) * (1 - 1e-3j),
                                    composed.Parameters(2.4, 120.0, 100.0, 5.0, 1e-5, 223e-6, 0.2, 0.8, 0.0))
    assert all(np.isfinite(o).all() for o in out)
