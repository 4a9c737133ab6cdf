"""Gamma-camera detectors: the photomultiplier tube and the parallel-hole collimator (exam Q2).

The 2006 paper asks four things of the gamma camera:

* Q2(a) how a photomultiplier tube (PMT) turns one photo-electron into a measurable pulse:
  :func:`pmt_gain` (``delta ** n``), :func:`pmt_cascade` (the mean number of electrons after
  each dynode) and :func:`pmt_gain_monte_carlo` (the random cascade, whose spread is what limits
  a scintillation camera's energy resolution);
* Q2(b) the properties of scintillation-crystal / PMT detectors (descriptive; see the notebook);
* Q2(c) the geometric resolution of one parallel hole by similar triangles,
  ``R = d (L + z) / L`` (:func:`collimator_resolution`) and its inverse
  ``L = d z / (R - d)`` (:func:`collimator_length_for_resolution`);
* Q2(d) the fraction of an on-axis point source's photons that reach the back of a collimator
  whose holes sit on rings (:func:`ring_hole_positions`), with the exam's all-or-nothing model
  (:func:`open_fraction`: a hole at radius ``r`` passes when ``r L / z <= d``).

Beyond the exam the module computes the *exact* transmission of every hole. From a point source
a straight ray passes a hole when it crosses both the entrance disc and the exit disc of that
hole. Projecting the exit disc from the source back onto the entrance plane shrinks it by
``s = z / (z + L)`` about the axis, so the rays that pass are those through the *lens* where the
entrance disc (centre ``c``, radius ``a = d/2``) overlaps the projected exit disc (centre ``s c``,
radius ``s a``), whose centres are ``D = r L / (z + L)`` apart (:func:`hole_pass_area`,
:func:`circle_overlap_area`). Dividing by the face area, as the exam does for a distant source,
gives :func:`hole_transmission` with ``weighting="uniform"``; weighting each point of the lens by
the solid angle it subtends (``weighting="isotropic"``) gives the exact answer for an isotropic
source. :func:`trace_photons` checks both with a vectorised Monte Carlo photon tracer, and
:func:`transmission_profile` / :func:`compare_models` show where the exam's model holds.

The students' copy of the library holds none of the graded functions (:func:`pmt_gain`,
:func:`collimator_resolution`, :func:`collimator_length_for_resolution`,
:func:`ring_hole_positions`, :func:`open_fraction`) nor the helpers that give their answers under
another name (:func:`pmt_cascade`, the two cut-off radii, :func:`transmission_profile`,
:func:`compare_models`): writing them is the question. The exact model and the photon tracer
are in both copies (docs/students-copy.md).

Geometry and units
------------------
Lengths in millimetres. The source is on the collimator axis at distance ``z`` in front of the
entrance face (plane ``Z = 0``); the exit face is the plane ``Z = L``. Hole centres are ``(x, y)``
positions on the face.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_int, as_points, as_positive, as_scalar

__all__ = [
    "circle_overlap_area",
    "collimator_length_for_resolution",
    "collimator_resolution",
    "compare_models",
    "disc_solid_angle",
    "exact_cutoff_radius",
    "exact_open_fraction",
    "exam_cutoff_radius",
    "hole_pass_area",
    "hole_pass_solid_angle",
    "hole_transmission",
    "open_fraction",
    "pmt_cascade",
    "pmt_gain",
    "pmt_gain_monte_carlo",
    "ring_hole_count",
    "ring_hole_positions",
    "trace_photons",
    "transmission_profile",
]


# ---------------------------------------------------------------------------------------------
# Q2(a): the photomultiplier tube


def pmt_gain(delta, n_dynodes):
    """Electrons reaching the anode per photo-electron leaving the photocathode (Q2(a)).

    Each dynode, held more positive than the one before, accelerates the electrons arriving from
    the previous stage; every impact knocks out on average ``delta`` secondary electrons, so
    after ``n`` dynodes one photo-electron has become ``G = delta ** n`` electrons.

    Parameters
    ----------
    delta : float
        Mean number of secondary electrons released per incident electron at each dynode (the
        secondary-emission ratio); positive, typically 3 to 6.
    n_dynodes : int
        Number of dynodes (non-negative integer; 0 means no multiplication, gain 1).

    Returns
    -------
    float
        The gain ``delta ** n_dynodes``.

    Raises
    ------
    ValueError
        If ``delta`` is not a single positive number, or ``n_dynodes`` is not a non-negative
        integer.

    Notes
    -----
    Q2(a) of the 2006 paper asks for a description of the tube; the gain ``G = delta^n`` is the
    quantitative content of "the current passing down the tube is amplified" at each dynode.

    Examples
    --------
    >>> pmt_gain(4.0, 10)          # a typical ten-dynode tube
    1048576.0
    >>> pmt_gain(5.0, 0)
    1.0
    """
    delta = as_scalar(as_positive(delta, "delta"), "delta")
    n = as_int(n_dynodes, "n_dynodes", minimum=0)
    return float(delta**n)


def pmt_cascade(delta, n_dynodes):
    """Mean number of electrons leaving the photocathode and each dynode, shape ``(n + 1,)``.

    Entry ``k`` is ``delta ** k``: 1 photo-electron, then ``delta`` after the first dynode, and
    so on; the last entry is the charge collected by the anode, :func:`pmt_gain` (Q2(a)).

    Examples
    --------
    >>> pmt_cascade(4.0, 3)
    array([ 1.,  4., 16., 64.])
    """
    delta = as_scalar(as_positive(delta, "delta"), "delta")
    n = as_int(n_dynodes, "n_dynodes", minimum=0)
    return delta ** np.arange(n + 1, dtype=np.float64)


def pmt_gain_monte_carlo(delta, n_dynodes, n_events, rng=None, photoelectrons=1):
    """Simulated anode charge of ``n_events`` pulses: a Poisson branching cascade (Q2(a)).

    Every electron striking a dynode releases a Poisson(``delta``) number of secondaries, so the
    number leaving stage ``k`` given ``N`` arriving is Poisson(``delta * N``). The mean of the
    result is ``photoelectrons * delta ** n``; for one photo-electron its relative variance is
    that of a Galton-Watson process with Poisson offspring,
    ``Var(G) / E(G)^2 = (1 - delta^-n) / (delta - 1)``, dominated by the first dynode: this is
    why a PMT's first stage is given the largest gain in practice.

    Parameters
    ----------
    delta : float
        Mean secondary-emission ratio per dynode, positive.
    n_dynodes : int
        Number of dynodes, non-negative.
    n_events : int
        Number of independent pulses to simulate, at least 1.
    rng : None, int or numpy.random.Generator
        Seed or generator for reproducible draws (NumPy's own ``Generator``: a subclass whose
        ``poisson`` returned its mean would turn the simulation into :func:`pmt_gain`).
    photoelectrons : int
        Photo-electrons starting each pulse (default 1).

    Returns
    -------
    numpy.ndarray
        Shape ``(n_events,)``, float64: electrons collected by the anode in each pulse.

    Raises
    ------
    ValueError
        Bad sizes, or ``rng`` a subclass of ``numpy.random.Generator``.
    """
    delta = as_scalar(as_positive(delta, "delta"), "delta")
    n = as_int(n_dynodes, "n_dynodes", minimum=0)
    n_events = as_int(n_events, "n_events", minimum=1)
    photoelectrons = as_int(photoelectrons, "photoelectrons", minimum=0)
    rng = _generator(rng)
    electrons = np.full(n_events, photoelectrons, dtype=np.int64)
    for _ in range(n):
        electrons = rng.poisson(delta * electrons)
    return electrons.astype(np.float64)


def _generator(rng):
    """NumPy's random generator for ``rng`` (``None``, a seed or a generator); ``ValueError``
    for a subclass of ``numpy.random.Generator``, whose draws could be anything (e.g. the mean:
    then the simulated cascade is the exact gain)."""
    if isinstance(rng, np.random.Generator) and type(rng) is not np.random.Generator:
        raise ValueError(f"rng must be a seed or a numpy.random.Generator, not a "
                         f"{type(rng).__name__}")
    return np.random.default_rng(rng)


# ---------------------------------------------------------------------------------------------
# Q2(c): resolution of one hole by similar triangles


def collimator_resolution(d, L, z):
    """Geometric resolution of a parallel hole, ``R = d (L + z) / L`` (Q2(c)).

    Seen from the point of the crystal behind the centre of a hole of diameter ``d`` and length
    ``L``, the lines through the edges of the hole's mouth form a cone: width ``d`` at the
    collimator face, a distance ``L`` from its apex, and width ``R`` at the source plane, a
    further ``z`` away. By similar triangles ``R / d = (L + z) / L``. Sources closer together
    than ``R`` are seen by the same points of the crystal and cannot be told apart. (The extreme
    rays that cross the hole from edge to opposite edge reach further, to a patch
    ``d (L + 2 z) / L`` wide, but from near its rim only a sliver of photons passes.)

    Parameters
    ----------
    d : float or array_like
        Hole diameter, positive.
    L : float or array_like
        Hole (collimator) length, positive.
    z : float or array_like
        Distance of the source in front of the collimator face, non-negative.

    Returns
    -------
    float or numpy.ndarray
        The resolution, in the units of the inputs; a float when all inputs are scalars,
        otherwise the broadcast array.

    Raises
    ------
    ValueError
        Non-positive ``d`` or ``L``, negative ``z``, or shapes that do not broadcast.

    Notes
    -----
    Q2(c) of the solutions: "by similar triangles". ``R`` is linear in ``z`` and equals ``d`` at
    the face: a collimator resolves best what touches it, and a longer hole slows the growth.
    Septal penetration and the crystal's intrinsic resolution are ignored.

    Examples
    --------
    The givens reconstructed for Q2(c): a 1 mm hole 200 mm long resolves 2 mm at 200 mm.

    >>> collimator_resolution(1.0, 200.0, 200.0)
    2.0
    """
    d = as_positive(d, "d")
    L = as_positive(L, "L")
    z = as_positive(z, "z", allow_zero=True)
    try:
        R = d * (L + z) / L
    except ValueError as exc:
        raise ValueError(f"d, L and z must broadcast together: {exc}") from None
    return float(R) if R.ndim == 0 else R


def collimator_length_for_resolution(d, R, z):
    """The hole length that gives resolution ``R`` at distance ``z``: ``L = d z / (R - d)`` (Q2(c)).

    This inverts :func:`collimator_resolution`. Since ``R = d (1 + z / L) > d`` for every finite
    length, a resolution at or below the hole diameter cannot be reached.

    Parameters
    ----------
    d : float or array_like
        Hole diameter, positive.
    R : float or array_like
        Required resolution at distance ``z``; must exceed ``d``.
    z : float or array_like
        Distance of the source in front of the collimator face, positive.

    Returns
    -------
    float or numpy.ndarray
        The length ``L``; a float when all inputs are scalars.

    Raises
    ------
    ValueError
        If ``R <= d`` anywhere (no finite hole achieves it), or ``d``, ``R`` or ``z`` is not
        positive, or the shapes do not broadcast.

    Examples
    --------
    >>> collimator_length_for_resolution(1.0, 2.0, 200.0)   # Q2(c): a 20 cm collimator
    200.0
    """
    d = as_positive(d, "d")
    R = as_positive(R, "R")
    z = as_positive(z, "z")
    try:
        excess = R - d
        L = d * z / np.where(excess > 0, excess, 1.0)
    except ValueError as exc:
        raise ValueError(f"d, R and z must broadcast together: {exc}") from None
    if np.any(excess <= 0):
        raise ValueError("R must be larger than the hole diameter d: a parallel hole never "
                         "resolves better than its own diameter")
    return float(L) if L.ndim == 0 else L


# ---------------------------------------------------------------------------------------------
# Q2(d): holes on rings and the exam's all-or-nothing model


def ring_hole_count(n_rings):
    """Number of holes in a centre hole plus ``n_rings`` rings of ``8k`` holes: ``1 + 4 n (n+1)``.

    Examples
    --------
    >>> ring_hole_count(2)     # Q2(d): the centre, 8 and 16
    25
    """
    n = as_int(n_rings, "n_rings", minimum=0)
    return 1 + 4 * n * (n + 1)


def ring_hole_positions(pitch, n_rings):
    """Centres of a collimator's holes: the centre hole and rings of ``8k`` holes (Q2(d)).

    Ring ``k`` (``k = 1 ... n_rings``) holds ``8k`` holes on the circle of radius ``k * pitch``,
    the first at angle 0 and the rest evenly spaced, so neighbouring holes on a ring are about
    ``2 pi k pitch / 8k ~ 0.79 pitch`` apart, like the spacing between rings.

    Parameters
    ----------
    pitch : float
        Radial spacing between rings, positive.
    n_rings : int
        Number of rings around the centre hole, non-negative.

    Returns
    -------
    numpy.ndarray
        Shape ``(1 + 4 n (n + 1), 2)``: the centre ``(0, 0)`` first, then ring 1 anticlockwise
        from angle 0, then ring 2, and so on.

    Raises
    ------
    ValueError
        Non-positive ``pitch``; negative or non-integer ``n_rings``.

    Examples
    --------
    >>> ring_hole_positions(10.0, 2).shape
    (25, 2)
    """
    pitch = as_scalar(as_positive(pitch, "pitch"), "pitch")
    n = as_int(n_rings, "n_rings", minimum=0)
    rings = [np.zeros((1, 2))]
    for k in range(1, n + 1):
        theta = 2.0 * np.pi * np.arange(8 * k) / (8 * k)
        rings.append(k * pitch * np.column_stack([np.cos(theta), np.sin(theta)]))
    return np.concatenate(rings, axis=0)


def _collimator_args(holes_xy, d, L, source_distance, collimator_radius=None):
    holes = as_points(holes_xy, 2, "holes_xy", min_count=0)
    d = as_scalar(as_positive(d, "d"), "d")
    L = as_scalar(as_positive(L, "L"), "L")
    z = as_scalar(as_positive(source_distance, "source_distance"), "source_distance")
    R = None
    if collimator_radius is not None:
        R = as_scalar(as_positive(collimator_radius, "collimator_radius"), "collimator_radius")
    return holes, d, L, z, R


def exam_cutoff_radius(d, L, source_distance):
    """Radius out to which the exam's model lets radiation through a hole: ``d z / L`` (Q2(d)).

    >>> exam_cutoff_radius(1.0, 40.0, 1000.0)
    25.0
    """
    d = as_scalar(as_positive(d, "d"), "d")
    L = as_scalar(as_positive(L, "L"), "L")
    z = as_scalar(as_positive(source_distance, "source_distance"), "source_distance")
    return d * z / L


def exact_cutoff_radius(d, L, source_distance):
    """Largest hole-centre radius at which *any* straight ray passes: ``d z / L + d / 2``.

    A ray entering at the hole's inner edge (radius ``r - d/2``) drifts outwards by
    ``(r - d/2) L / z`` over the length of the hole; it still leaves by the outer edge
    (``r + d/2``) when ``(r - d/2) L / z <= d``. The exam's ``r L / z <= d`` drops the ``d/2``.

    >>> exact_cutoff_radius(1.0, 40.0, 1000.0)
    25.5
    """
    d = float(as_scalar(as_positive(d, "d"), "d"))
    return exam_cutoff_radius(d, L, source_distance) + d / 2.0


def open_fraction(holes_xy, d, L, source_distance, collimator_radius):
    """Fraction of the photons reaching the face that reach the back: the exam's model (Q2(d)).

    A hole whose centre is at radius ``r`` is *open* when ``r * L / source_distance <= d``:
    a ray entering at one side of the hole drifts sideways by ``r L / z`` over the hole's
    length, and the exam lets it through when that drift does not exceed the diameter. Open
    holes pass all the radiation that falls on them and the others none. With the source far away
    (ten collimator diameters in the exam) the radiation is taken as uniform over the face, so the
    fraction is the open holes' total area over the face area.

    Parameters
    ----------
    holes_xy : array_like, shape (n, 2)
        Hole centres on the collimator face (e.g. from :func:`ring_hole_positions`).
    d : float
        Hole diameter, positive.
    L : float
        Hole length, positive.
    source_distance : float
        Distance of the on-axis point source from the face, positive.
    collimator_radius : float
        Radius of the collimator face, positive.

    Returns
    -------
    float
        ``n_open * pi (d/2)^2 / (pi collimator_radius^2)``.

    Raises
    ------
    ValueError
        ``holes_xy`` not of shape ``(n, 2)``; any size not positive.

    Notes
    -----
    Q2(d) of the solutions: 25 holes pass (the centre, 8 and 16), open area
    ``0.5^2 pi 25 = 19.635 mm^2``, face ``50^2 pi = 7853.98 mm^2``, fraction 0.25 %. The hole
    length, pitch and source distance used here (L = 40 mm, pitch 10 mm, z = 1 m) are our
    reconstruction of the missing question text; they make the cut-off radius ``d z / L`` the
    solutions' 25 mm. :func:`exact_open_fraction` gives the exact figure.

    Examples
    --------
    >>> holes = ring_hole_positions(10.0, 4)
    >>> round(open_fraction(holes, 1.0, 40.0, 1000.0, 50.0), 6)
    0.0025
    """
    holes, d, L, z, R = _collimator_args(holes_xy, d, L, source_distance, collimator_radius)
    r = np.hypot(holes[:, 0], holes[:, 1])
    n_open = int(np.count_nonzero(r * L / z <= d))
    return float(n_open * np.pi * (d / 2.0) ** 2 / (np.pi * R**2))


# ---------------------------------------------------------------------------------------------
# Beyond the exam: exact transmission of each hole


def circle_overlap_area(r1, r2, D):
    """Area of the lens where two discs of radii ``r1``, ``r2`` with centres ``D`` apart overlap.

    ``0`` when ``D >= r1 + r2``, ``pi min(r1, r2)^2`` when one disc lies inside the other
    (``D <= |r1 - r2|``), and otherwise the sum of the two circular segments,
    ``r1^2 acos(c1) + r2^2 acos(c2) - sqrt((-D+r1+r2)(D+r1-r2)(D-r1+r2)(D+r1+r2)) / 2`` with
    ``c1 = (D^2 + r1^2 - r2^2) / (2 D r1)`` and ``c2 = (D^2 + r2^2 - r1^2) / (2 D r2)``.
    Broadcasts.

    Raises
    ------
    ValueError
        Non-positive radius or negative distance.

    Examples
    --------
    >>> round(circle_overlap_area(1.0, 1.0, 0.0), 12) == round(np.pi, 12)
    True
    """
    r1 = as_positive(r1, "r1")
    r2 = as_positive(r2, "r2")
    D = as_positive(D, "D", allow_zero=True)
    r1, r2, D = np.broadcast_arrays(r1, r2, D)
    out = np.zeros(D.shape)
    inside = D <= np.abs(r1 - r2)
    out[inside] = np.pi * np.minimum(r1, r2)[inside] ** 2
    part = ~inside & (D < r1 + r2)
    a, b, c = r1[part], r2[part], D[part]
    c1 = np.clip((c**2 + a**2 - b**2) / (2 * c * a), -1.0, 1.0)
    c2 = np.clip((c**2 + b**2 - a**2) / (2 * c * b), -1.0, 1.0)
    k = (-c + a + b) * (c + a - b) * (c - a + b) * (c + a + b)
    lens = a**2 * np.arccos(c1) + b**2 * np.arccos(c2) - 0.5 * np.sqrt(np.maximum(k, 0.0))
    out[part] = np.maximum(lens, 0.0)  # rounding can leave -1e-9 where the discs just touch
    return float(out) if out.ndim == 0 else out


def hole_pass_area(r, d, L, source_distance):
    """Area of a hole's entrance through which straight rays from the source reach the exit.

    The exit disc, projected from the on-axis source onto the entrance plane, is a disc of
    radius ``s d / 2`` centred at ``s r`` with ``s = z / (z + L)``; the rays that pass cross the
    lens where it overlaps the entrance disc (radius ``d / 2``, centred at ``r``). The centres are
    ``D = r L / (z + L)`` apart, so the area is ``circle_overlap_area(d/2, s d/2, D)``.

    Parameters
    ----------
    r : float or array_like
        Radius of each hole's centre from the axis, non-negative.
    d, L, source_distance : float
        Hole diameter, hole length and source distance ``z``, positive.

    Returns
    -------
    float or numpy.ndarray
        The lens area(s), shape of ``r``.

    Examples
    --------
    The centre hole of Q2(d) passes ``s^2`` of its area, ``s = 1000 / 1040``:

    >>> round(hole_pass_area(0.0, 1.0, 40.0, 1000.0) / (np.pi * 0.25), 6)
    0.924556
    """
    r = as_positive(r, "r", allow_zero=True)
    d = as_scalar(as_positive(d, "d"), "d")
    L = as_scalar(as_positive(L, "L"), "L")
    z = as_scalar(as_positive(source_distance, "source_distance"), "source_distance")
    s = z / (z + L)
    return circle_overlap_area(d / 2.0, s * d / 2.0, r * L / (z + L))


def _cap_fraction(rho, z):
    """``1 - z / sqrt(rho^2 + z^2)``: the solid angle of an on-axis disc of radius ``rho``
    divided by ``2 pi`` (written so that it keeps its precision when ``rho << z``)."""
    h = np.hypot(rho, z)
    return rho**2 / (h * (h + z))


#: Gauss-Legendre nodes and weights on [0, 1] used by the lens quadrature.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(96)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


def _lens_polar_integral(r, a, s, G):
    """``integral over the lens of g(rho) dA`` for a radial weight ``g`` with ``G' = rho g``.

    The lens is entrance disc (centre ``r``, radius ``a``) intersected with the projected exit
    disc (centre ``s r``, radius ``s a``). A ray from the axis at angle ``phi`` to the hole's
    direction crosses the entrance disc between ``m - q`` and ``m + q`` (``m = r cos phi``,
    ``q = sqrt(a^2 - r^2 sin^2 phi)``) and the projected exit disc between ``s (m - q)`` and
    ``s (m + q)``, so within the lens between ``max(m - q, 0)`` and ``s (m + q)``. The integral is
    ``sum over rays of G(outer) - G(inner)``, evaluated by Gauss-Legendre quadrature after the
    substitution ``sin phi = (a / r) sin theta`` that removes the square-root end points.
    """
    r = np.asarray(r, dtype=np.float64)
    out = np.zeros(r.shape)
    # Holes that contain the axis (r < a): the projected exit disc lies inside the entrance disc
    # and every ray from the axis crosses it from 0 to s (m + q).
    inner = r < a
    if np.any(inner):
        ri = r[inner][:, None]
        phi = np.pi * _GL_X[None, :]
        m = ri * np.cos(phi)
        q = np.sqrt(np.maximum(a**2 - (ri * np.sin(phi)) ** 2, 0.0))
        vals = G(s * (m + q)) - G(np.zeros_like(m))
        out[inner] = 2.0 * np.pi * (vals @ _GL_W)
    outer = (r >= a) & (r * (1.0 - s) < a * (1.0 + s))
    if np.any(outer):
        ro = r[outer][:, None]
        sin2_end = (a**2 * (1 + s) ** 2 - ro**2 * (1 - s) ** 2) / (4 * a**2 * s)
        theta_end = np.arcsin(np.sqrt(np.clip(sin2_end, 0.0, 1.0)))
        theta = theta_end * _GL_X[None, :]
        sin_alpha = a / ro
        sin_phi = sin_alpha * np.sin(theta)
        cos_phi = np.sqrt(np.maximum(1.0 - sin_phi**2, 0.0))
        m = ro * cos_phi
        q = a * np.cos(theta)
        # d phi / d theta = sin(alpha) cos(theta) / cos(phi); cos(phi) >= cos(theta) > 0 here
        jac = sin_alpha * np.cos(theta) / np.where(cos_phi > 0, cos_phi, 1.0)
        vals = np.maximum(G(s * (m + q)) - G(np.maximum(m - q, 0.0)), 0.0) * jac
        out[outer] = 2.0 * theta_end[:, 0] * (vals @ _GL_W)
    return out


def hole_pass_solid_angle(r, d, L, source_distance):
    """Solid angle (steradians) of the rays from the source that pass one hole.

    The same lens as :func:`hole_pass_area`, but each element ``dA`` at distance ``rho`` from the
    axis counts ``z dA / (rho^2 + z^2)^{3/2}``, the solid angle it subtends at the source. The
    integral over the lens is done exactly in the radial direction (the weight integrates to
    ``1 - z / sqrt(rho^2 + z^2)``) and by 96-point Gauss-Legendre quadrature over angle.

    Parameters
    ----------
    r : float or array_like
        Radius of each hole's centre from the axis, non-negative.
    d, L, source_distance : float
        Hole diameter, length and source distance, positive.

    Returns
    -------
    float or numpy.ndarray
        Solid angle of each hole's passing rays, shape of ``r``.
    """
    r = as_positive(r, "r", allow_zero=True)
    d = as_scalar(as_positive(d, "d"), "d")
    L = as_scalar(as_positive(L, "L"), "L")
    z = as_scalar(as_positive(source_distance, "source_distance"), "source_distance")
    s = z / (z + L)
    out = _lens_polar_integral(np.atleast_1d(r), d / 2.0, s, lambda rho: _cap_fraction(rho, z))
    return float(out[0]) if r.ndim == 0 else out.reshape(r.shape)


def disc_solid_angle(radius, source_distance):
    """Solid angle of an on-axis disc seen from distance ``z``: ``2 pi (1 - z / sqrt(z^2 + R^2))``.

    >>> round(disc_solid_angle(50.0, 1000.0), 8)
    0.00783929
    """
    radius = as_positive(radius, "radius")
    z = as_positive(source_distance, "source_distance")
    out = 2.0 * np.pi * _cap_fraction(radius, z)
    return float(out) if np.ndim(out) == 0 else out


_WEIGHTINGS = ("uniform", "isotropic")


def hole_transmission(holes_xy, d, L, source_distance, collimator_radius, weighting="uniform"):
    """Exact fraction of the photons striking the face that leave through each hole, ``(n,)``.

    ``weighting="uniform"`` takes the photons as uniform over the face, as the exam does for a
    distant source: hole ``j`` passes ``hole_pass_area(r_j) / (pi R^2)``. ``"isotropic"`` is exact
    for an isotropic point source: ``hole_pass_solid_angle(r_j) / disc_solid_angle(R)``. The two
    agree when the face is small compared with the source distance.

    Parameters
    ----------
    holes_xy : array_like, shape (n, 2)
        Hole centres.
    d, L, source_distance, collimator_radius : float
        Hole diameter and length, source distance and face radius, positive.
    weighting : {"uniform", "isotropic"}
        How the photons are spread over the face.

    Returns
    -------
    numpy.ndarray
        Shape ``(n,)``: each hole's share of the photons that reach the face.

    Raises
    ------
    ValueError
        Bad shapes, non-positive sizes or an unknown ``weighting``.

    Notes
    -----
    Holes are assumed not to overlap and to lie on the face; a photon is absorbed by the septa
    unless it enters and leaves the same hole.
    """
    holes, d, L, z, R = _collimator_args(holes_xy, d, L, source_distance, collimator_radius)
    if weighting not in _WEIGHTINGS:
        raise ValueError(f"weighting must be one of {_WEIGHTINGS}, got {weighting!r}")
    r = np.hypot(holes[:, 0], holes[:, 1])
    if weighting == "uniform":
        return np.atleast_1d(hole_pass_area(r, d, L, z)) / (np.pi * R**2)
    return np.atleast_1d(hole_pass_solid_angle(r, d, L, z)) / disc_solid_angle(R, z)


def exact_open_fraction(holes_xy, d, L, source_distance, collimator_radius, weighting="uniform"):
    """Exact counterpart of :func:`open_fraction`: the sum of :func:`hole_transmission`.

    >>> holes = ring_hole_positions(10.0, 4)
    >>> f = exact_open_fraction(holes, 1.0, 40.0, 1000.0, 50.0)
    >>> 0.0005 < f < open_fraction(holes, 1.0, 40.0, 1000.0, 50.0)
    True
    """
    return float(np.sum(hole_transmission(holes_xy, d, L, source_distance, collimator_radius,
                                          weighting)))


# ---------------------------------------------------------------------------------------------
# Monte Carlo photon tracer


def trace_photons(holes_xy, d, L, source_distance, collimator_radius, n_photons,
                  rng=None, emission="isotropic", chunk=50_000, return_points=False):
    """Trace straight photon paths from an on-axis point source through the collimator.

    Each photon leaves the source towards the collimator face and meets the entrance plane at
    ``p``; it continues in a straight line and meets the exit plane at ``p (z + L) / z``. It is
    counted through hole ``j`` only when both points lie inside hole ``j``'s disc (the hole is a
    convex cylinder, so the whole path between them is then inside it); every other photon is
    absorbed by the septa.

    Parameters
    ----------
    holes_xy : array_like, shape (n, 2)
        Hole centres (non-overlapping holes on the face).
    d, L, source_distance, collimator_radius : float
        Hole diameter and length, source distance and face radius, positive.
    n_photons : int
        Number of photons striking the face, at least 1.
    rng : None, int or numpy.random.Generator
        Seed or generator.
    emission : {"isotropic", "uniform"}
        ``"isotropic"``: directions uniform in solid angle within the cone the face subtends
        (``cos(theta)`` uniform on ``[z / sqrt(z^2 + R^2), 1]``), the physical point source.
        ``"uniform"``: aim points uniform in area over the face, the exam's far-source
        assumption.
    chunk : int
        Photons processed at once (memory ``~ chunk * n_holes``).
    return_points : bool
        Also return the entrance points and the hole each photon passed (-1 if absorbed).

    Returns
    -------
    fraction : float
        Fraction of the photons that reach the back.
    std_error : float
        Its binomial standard error ``sqrt(f (1 - f) / n)``.
    counts : numpy.ndarray
        Shape ``(n_holes,)``: photons through each hole.
    points, hole : numpy.ndarray
        Only with ``return_points``: ``(n_photons, 2)`` entrance points and ``(n_photons,)``
        hole indices.
    """
    holes, d, L, z, R = _collimator_args(holes_xy, d, L, source_distance, collimator_radius)
    n_photons = as_int(n_photons, "n_photons", minimum=1)
    chunk = as_int(chunk, "chunk", minimum=1)
    if emission not in _WEIGHTINGS:
        raise ValueError(f"emission must be one of {_WEIGHTINGS}, got {emission!r}")
    rng = _generator(rng)
    a2 = (d / 2.0) ** 2
    grow = (z + L) / z
    counts = np.zeros(len(holes), dtype=np.int64)
    all_points, all_hole = [], []
    cos_max = z / np.hypot(z, R)
    c2 = (holes**2).sum(axis=1)
    for start in range(0, n_photons, chunk):
        n = min(chunk, n_photons - start)
        azimuth = rng.uniform(0.0, 2.0 * np.pi, n)
        if emission == "uniform":
            rho = R * np.sqrt(rng.uniform(0.0, 1.0, n))
        else:
            cos_t = rng.uniform(cos_max, 1.0, n)
            rho = z * np.sqrt(1.0 - cos_t**2) / cos_t
        p = rho[:, None] * np.column_stack([np.cos(azimuth), np.sin(azimuth)])
        hole = np.full(n, -1, dtype=np.int64)
        if len(holes):
            # |p - c|^2 = |p|^2 - 2 p.c + |c|^2 as one matrix product; then the exact test for
            # the few photons that land in some hole's entrance (with a margin for rounding).
            d_in = (p**2).sum(axis=1)[:, None] - 2.0 * p @ holes.T + c2[None, :]
            cand = np.flatnonzero((d_in <= a2 * (1 + 1e-6) + 1e-9).any(axis=1))
            pc = p[cand]
            e_in = ((pc[:, None, :] - holes[None, :, :]) ** 2).sum(axis=2)
            e_out = ((grow * pc[:, None, :] - holes[None, :, :]) ** 2).sum(axis=2)
            ok = (e_in <= a2) & (e_out <= a2)
            passed = ok.any(axis=1)
            hole[cand[passed]] = ok[passed].argmax(axis=1)
            counts += np.bincount(hole[cand[passed]], minlength=len(holes))
        if return_points:
            all_points.append(p)
            all_hole.append(hole)
    f = counts.sum() / n_photons
    se = float(np.sqrt(f * (1.0 - f) / n_photons))
    if return_points:
        return float(f), se, counts, np.concatenate(all_points), np.concatenate(all_hole)
    return float(f), se, counts


# ---------------------------------------------------------------------------------------------
# Where the exam's model holds


def transmission_profile(r, d, L, source_distance):
    """Per-hole transmission against hole radius: exact vs the exam's all-or-nothing.

    Returns ``(exact, exam)``, both shaped like ``r``: ``exact = hole_pass_area / (pi d^2 / 4)``,
    the share of the radiation falling on the hole that gets through, and ``exam`` the 0/1
    verdict ``r L / z <= d``. The exact curve starts at ``s^2 = (z / (z + L))^2`` on the axis and
    falls almost linearly to nearly 0 at the exam's cut-off ``d z / L`` (exactly 0 at
    ``d z / L + d / 2``): the exam counts a hole whole as soon as *any* ray passes it. Averaged
    over the face inside the exam's cut-off it is only about 1/4 (the overlap area of two equal
    discs integrated over all offsets is the product of their areas), so the exam's model
    overstates the throughput by about 4 whenever several rings are open; it is accurate only
    when every open hole has ``r L / z << d`` (thin collimator or distant source).

    Examples
    --------
    >>> exact, exam = transmission_profile(np.array([0.0, 30.0]), 1.0, 40.0, 1000.0)
    >>> exam.tolist(), bool(exact[1] == 0.0)
    ([1.0, 0.0], True)
    """
    r = as_positive(r, "r", allow_zero=True)
    d = as_scalar(as_positive(d, "d"), "d")
    L = as_scalar(as_positive(L, "L"), "L")
    z = as_scalar(as_positive(source_distance, "source_distance"), "source_distance")
    exact = np.asarray(hole_pass_area(r, d, L, z)) / (np.pi * d**2 / 4.0)
    exam = (r * L / z <= d).astype(np.float64)
    return exact, exam


def compare_models(holes_xy, d, L, source_distances, collimator_radius):
    """The exam's fraction and the exact ones over a range of source distances.

    Returns ``(exam, uniform, isotropic)``, each shaped like ``source_distances``:
    :func:`open_fraction`, and :func:`exact_open_fraction` with the two weightings. The ratio
    ``exam / uniform`` tends to ``1 / s^2 ~ 1`` only while the exam's cut-off radius ``d z / L``
    stays inside the first ring (only the centre hole open, far source); once rings open it
    saw-tooths towards about 4.
    """
    zs = as_positive(source_distances, "source_distances")
    flat = np.atleast_1d(zs).ravel()
    exam = np.array([open_fraction(holes_xy, d, L, z, collimator_radius) for z in flat])
    uni = np.array([exact_open_fraction(holes_xy, d, L, z, collimator_radius, "uniform")
                    for z in flat])
    iso = np.array([exact_open_fraction(holes_xy, d, L, z, collimator_radius, "isotropic")
                    for z in flat])
    shape = np.shape(zs)
    return exam.reshape(shape), uni.reshape(shape), iso.reshape(shape)
