"""Contrast between antiparallel domains with an electrostatic background (Section IV.3).

Over :math:`c^+` and :math:`c^-` domains the first-harmonic response is (Eqs. 37-38)

.. math::

    PR_\\pm = \\pm d_{eff} + d_{el} e^{i\\psi}, \\qquad d_{el} = G_{elec}(V_{dc} - V_{av}),

where :math:`\\psi` is the phase of the electrostatic relative to the electromechanical
response.  Throughout this module ``d_eff`` and ``d_el`` are real and signed (the sign of
``d_el`` follows that of :math:`V_{dc} - V_{av}`), ``psi`` is in radians, and all functions
broadcast over NumPy arrays.

**Phase-difference convention.**  :math:`\\Delta\\varphi = \\arg PR_+ - \\arg PR_-`, wrapped to
the half-open interval :math:`(-\\pi, \\pi]` (so a pure piezoresponse gives exactly
:math:`+\\pi`).  Since :math:`PR_+ \\overline{PR_-} = d_{el}^2 - d_{eff}^2 - 2 i\\, d_{el} d_{eff}
\\sin\\psi`, the correct counterpart of the paper's Eq. 39 is

.. math::

    \\tan\\Delta\\varphi = \\frac{2 d_{el} d_{eff} \\sin\\psi}{d_{eff}^2 - d_{el}^2}.

Two families of functions are provided:

* exact results and the correct leading-order limits, generated from
  ``derivations/domain_contrast.py`` (``generated/formulas.py``); ``tests/test_domains.py``
  checks them against complex arithmetic and checks the order of their error;
* ``paper_*`` functions returning the paper's formulas **as printed, see the errata**, kept
  only so that the printed and the correct forms can be compared (generated from their one
  transcription, ``derivations/paper/printed.py``).

References
----------
Jesse, Baddorf, Kalinin (2006), "Dynamic behavior in piezoresponse force microscopy",
Section IV.3, Eqs. 37-40.
"""
from __future__ import annotations

import numpy as np

from ..generated import formulas


def electrostatic_amplitude(g_elec, v_dc, v_av):
    """Electrostatic term :math:`d_{el} = G_{elec}(V_{dc} - V_{av})` of Eqs. 37-38.

    Parameters
    ----------
    g_elec : array_like
        Electrostatic contribution per volt of tip-surface potential difference.
    v_dc, v_av : array_like
        Tip dc bias and average surface potential (V).

    Returns
    -------
    ndarray
        :math:`d_{el}`, in the units of ``g_elec`` times volts.

    Examples
    --------
    >>> float(electrostatic_amplitude(2.0, 1.5, 0.5))
    2.0
    """
    return formulas.electrostatic_term(np.asarray(g_elec), np.asarray(v_dc), np.asarray(v_av))


def _arrays(d_eff, d_el, psi):
    """The two terms as arrays and the phase as a float array, as every formula of this module takes them."""
    return np.asarray(d_eff), np.asarray(d_el), np.asarray(psi, dtype=float)


def domain_responses(d_eff, d_el, psi):
    """Complex responses :math:`PR_+` and :math:`PR_-` over antiparallel domains (Eqs. 37-38).

    Parameters
    ----------
    d_eff : array_like
        Electromechanical response of the :math:`c^+` domain (real, signed).
    d_el : array_like
        Electrostatic term :math:`G_{elec}(V_{dc} - V_{av})` (real, signed).
    psi : array_like
        Phase of the electrostatic relative to the electromechanical response (rad).

    Returns
    -------
    pr_plus, pr_minus : ndarray of complex
        :math:`\\pm d_{eff} + d_{el} e^{i\\psi}`.

    Examples
    --------
    >>> [complex(pr) for pr in domain_responses(1.0, 0.5, 0.0)]
    [(1.5+0j), (-0.5+0j)]
    """
    args = _arrays(d_eff, d_el, psi)
    return formulas.domain_response_plus(*args), formulas.domain_response_minus(*args)


def domain_amplitudes(d_eff, d_el, psi):
    """Exact amplitudes :math:`|PR_\\pm| = \\sqrt{d_{eff}^2 + d_{el}^2 \\pm 2 d_{eff} d_{el}\\cos\\psi}`.

    Arguments as in :func:`domain_responses`; returns ``amp_plus, amp_minus``.  Evaluated as
    ``hypot(d_eff ± d_el cos psi, d_el sin psi)``, which cannot round to the square root of a
    negative number.

    Examples
    --------
    >>> [round(float(a), 12) for a in domain_amplitudes(3.0, 4.0, np.pi / 2)]
    [5.0, 5.0]
    """
    args = _arrays(d_eff, d_el, psi)
    return formulas.domain_amplitude_plus(*args), formulas.domain_amplitude_minus(*args)


def _half_open(angle):
    """Map -pi to pi: atan2 returns -pi when the imaginary part is a negative zero."""
    return np.where(angle <= -np.pi, np.pi, angle)


def _wrap(angle):
    """Wrap angles to (-pi, pi]."""
    return _half_open(np.angle(np.exp(1j * np.asarray(angle, dtype=float))))


def phase_difference(d_eff, d_el, psi):
    """Exact phase difference :math:`\\Delta\\varphi = \\arg PR_+ - \\arg PR_-` in (-pi, pi].

    Arguments as in :func:`domain_responses`; returns radians.  Computed as
    ``atan2(-2 d_el d_eff sin psi, d_el**2 - d_eff**2)``, the argument of
    :math:`PR_+ \\overline{PR_-}`.

    Examples
    --------
    >>> float(phase_difference(1.0, 0.0, 0.3))  # pure piezoresponse: exactly pi
    3.141592653589793
    >>> abs(float(phase_difference(0.0, 1.0, 0.3)))  # pure electrostatics: no contrast
    0.0
    """
    return _half_open(formulas.domain_phase_difference(*_arrays(d_eff, d_el, psi)))


def _larger_term_positive(d_eff, d_el, psi, larger):
    """The arguments with the sign of ``larger`` (one of the two terms) taken out of both terms.

    The leading-order amplitudes were derived with the larger term positive; PR -> -PR
    (d_eff, d_el -> -d_eff, -d_el) keeps both amplitudes.
    """
    sign = np.sign(larger)
    return sign * d_eff, sign * d_el, psi


def amplitudes_small_electrostatic(d_eff, d_el, psi):
    """Leading-order amplitudes for :math:`|d_{el}| \\ll |d_{eff}|`.

    :math:`|PR_\\pm| \\approx |d_{eff}| \\pm \\operatorname{sgn}(d_{eff})\\, d_{el}\\cos\\psi`
    (which is :math:`d_{eff} \\pm d_{el}\\cos\\psi` for :math:`d_{eff} > 0`); the absolute
    error is :math:`O(d_{el}^2/|d_{eff}|)`.  Arguments as in :func:`domain_responses`, ``d_eff``
    nonzero; returns ``amp_plus, amp_minus``.

    Examples
    --------
    >>> [float(a) for a in amplitudes_small_electrostatic(1.0, 0.01, 0.0)]
    [1.01, 0.99]
    """
    args = _larger_term_positive(*_arrays(d_eff, d_el, psi), larger=d_eff)
    return (formulas.domain_amplitude_plus_small_electrostatic(*args),
            formulas.domain_amplitude_minus_small_electrostatic(*args))


def phase_difference_small_electrostatic(d_eff, d_el, psi):
    """Leading-order phase difference for :math:`|d_{el}| \\ll |d_{eff}|`.

    :math:`\\Delta\\varphi \\approx \\pi + 2 (d_{el}/d_{eff}) \\sin\\psi`, wrapped to
    (-pi, pi]; equivalently :math:`|\\Delta\\varphi| \\approx \\pi - 2 |d_{el}/d_{eff}|
    |\\sin\\psi|`.  The deviation from 180 degrees is *first* order in the electrostatic term
    and the error is :math:`O((d_{el}/d_{eff})^3)`.  (The paper's Eq. 40, see
    :func:`paper_eq40_phase_difference`, has a second-order deviation instead.)  Arguments as in
    :func:`domain_responses`, ``d_eff`` nonzero; returns radians.

    Examples
    --------
    >>> round(float(phase_difference_small_electrostatic(1.0, -0.01, np.pi / 2)), 6)
    3.121593
    """
    return _wrap(formulas.domain_phase_difference_small_electrostatic(*_arrays(d_eff, d_el, psi)))


def amplitudes_small_piezo(d_eff, d_el, psi):
    """Leading-order amplitudes for :math:`|d_{eff}| \\ll |d_{el}|`.

    :math:`|PR_\\pm| \\approx |d_{el}| \\pm \\operatorname{sgn}(d_{el})\\, d_{eff}\\cos\\psi`;
    the absolute error is :math:`O(d_{eff}^2/|d_{el}|)`.  Arguments as in :func:`domain_responses`,
    ``d_el`` nonzero; returns ``amp_plus, amp_minus``.

    Examples
    --------
    >>> [float(a) for a in amplitudes_small_piezo(0.01, -1.0, 0.0)]
    [0.99, 1.01]
    """
    args = _larger_term_positive(*_arrays(d_eff, d_el, psi), larger=d_el)
    return formulas.domain_amplitude_plus_small_piezo(*args), formulas.domain_amplitude_minus_small_piezo(*args)


def phase_difference_small_piezo(d_eff, d_el, psi):
    """Leading-order phase difference for :math:`|d_{eff}| \\ll |d_{el}|`.

    :math:`\\Delta\\varphi \\approx -2 (d_{eff}/d_{el}) \\sin\\psi`, with error
    :math:`O((d_{eff}/d_{el})^3)`: the contrast between the domains nearly vanishes.  Arguments
    as in :func:`domain_responses`, ``d_el`` nonzero; returns radians.

    Examples
    --------
    >>> float(phase_difference_small_piezo(0.01, 1.0, np.pi / 2))
    -0.02
    """
    return formulas.domain_phase_difference_small_piezo(*_arrays(d_eff, d_el, psi))


def paper_eq39_amplitudes(d_eff, d_el, phi):
    """Eq. 39 amplitudes as printed, see the errata: :math:`\\sqrt{d_{eff}^2 + d_{el}^2 \\pm d_{eff} d_{el}\\cos\\varphi}`.

    The printed cross term lacks the factor 2 of :func:`domain_amplitudes` (and the printed
    angle is :math:`\\varphi`, where :math:`\\psi` is meant).  Kept for comparison only.

    Parameters
    ----------
    d_eff, d_el : array_like
        As in :func:`domain_responses`.
    phi : array_like
        The angle in the printed formula (rad).

    Returns
    -------
    amp_plus, amp_minus : ndarray
        The printed :math:`PR_+` and :math:`PR_-`.

    Examples
    --------
    >>> [float(a) for a in paper_eq39_amplitudes(1.0, 1.0, 0.0)]  # exact: 2 and 0
    [1.7320508075688772, 1.0]
    """
    args = _arrays(d_eff, d_el, phi)
    return formulas.paper_eq39_amplitude_plus(*args), formulas.paper_eq39_amplitude_minus(*args)


def paper_eq39_tan_phase(d_el, psi, pr_plus, pr_minus):
    """Eq. 39 phase shift as printed, see the errata.

    :math:`\\tan\\varphi = 2 d_{el}(PR_- - PR_+)\\sin\\psi / (d_{el}^2(1 - \\cos 2\\psi) + 2 PR_+ PR_-)`.
    The paper does not say whether :math:`PR_\\pm` are amplitudes or signed responses; they
    are taken as given.  The correct relation is
    :math:`\\tan\\Delta\\varphi = 2 d_{el} d_{eff}\\sin\\psi / (d_{eff}^2 - d_{el}^2)` (module
    docstring).  Kept for comparison only.

    Parameters
    ----------
    d_el, psi : array_like
        As in :func:`domain_responses`.
    pr_plus, pr_minus : array_like
        The quantities :math:`PR_+` and :math:`PR_-` of the printed formula.

    Returns
    -------
    ndarray
        The printed :math:`\\tan\\varphi`.

    Examples
    --------
    >>> float(paper_eq39_tan_phase(1.0, np.pi / 2, 1.0, 1.0))
    0.0
    """
    return formulas.paper_eq39_tan_phase(np.asarray(d_el), np.asarray(psi, dtype=float),
                                         np.asarray(pr_plus), np.asarray(pr_minus))


def paper_eq40_phase_difference(d_eff, d_el, psi):
    """Eq. 40 as printed, see the errata: :math:`\\Delta\\varphi = \\pi - \\sin(2\\psi)\\, d_{el}^2/d_{eff}^2`.

    The correct small-electrostatic limit, :func:`phase_difference_small_electrostatic`,
    deviates from pi at first order in :math:`d_{el}/d_{eff}` with a :math:`\\sin\\psi`
    dependence.  Kept for comparison only.  Arguments as in :func:`domain_responses`; returns
    radians.

    Examples
    --------
    >>> round(float(paper_eq40_phase_difference(1.0, 0.1, np.pi / 4)), 6)
    3.131593
    """
    return formulas.paper_eq40_phase_difference(*_arrays(d_eff, d_el, psi))


def paper_small_piezo_phase_difference(d_eff, d_el, psi):
    """Small-piezoresponse phase difference as printed (Section IV.3), see the errata.

    :math:`\\Delta\\varphi = 2\\sin(2\\psi)\\, d_{eff} / (d_{el}(\\cos 2\\psi - 3))`.  The correct
    limit is :math:`-2 (d_{eff}/d_{el})\\sin\\psi` (:func:`phase_difference_small_piezo`);
    the printed form equals it times :math:`\\cos\\psi/(1 + \\sin^2\\psi)`.  Kept for
    comparison only.  Arguments as in :func:`domain_responses`; returns radians.

    Examples
    --------
    >>> round(float(paper_small_piezo_phase_difference(0.01, 1.0, np.pi / 3)), 6)  # correct: -0.017321
    -0.004949
    """
    return formulas.paper_small_piezo_phase_difference(*_arrays(d_eff, d_el, psi))
