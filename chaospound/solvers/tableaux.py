"""Butcher tableaux and step-size controllers of the explicit Runge-Kutta methods, as data.

A method is a :class:`Method` value: its tableau (arrays below), the names of
its stepper, error estimate, dense output and step-size controller in
:mod:`.steppers`, :mod:`.errors` and :mod:`.controllers`, and its counts.
:mod:`chaospound.engine.compose` binds them into a composition; no kernel asks
which method it runs. Adding an explicit method is one tableau, one
:class:`Method` in :data:`METHODS` and one row of tests/test_solvers.py.

* ``dopri5``    Dormand & Prince 5(4), FSAL, with the 4th-order continuous
  extension of Hairer, Norsett & Wanner (1993) sec. II.6 (identical to the
  ``P`` matrix of scipy's RK45); Hairer's PI step-size controller. Its step is
  unrolled (:func:`.steppers.dopri5_step`, the scalars ``_A21 ...`` below).
* ``cash-karp`` Cash & Karp 5(4) as in Press et al., Numerical Recipes (2nd
  ed.) sec. 16.2: the 5th-order solution is propagated, the difference to the
  embedded 4th-order one is the error, scaled as in ``rkqs``/``odeint`` (the
  paper's "0.1 %" is ``rtol = 1e-3``); cubic Hermite dense output.
* ``rk4``       the classical fourth-order method, fixed step (no error
  estimate); cubic Hermite dense output.
* ``dop853``    Dormand & Prince 8(5,3) as in Hairer's dop853 and
  scipy.integrate.DOP853: combined 5th/3rd-order error estimate and the
  7th-order dense output (3 extra stages).
"""

from typing import NamedTuple

import numpy as np


class Method(NamedTuple):
    """An explicit Runge-Kutta method, as the engine composes it."""

    name: str
    order: int  #: order of the propagated solution
    error_order: int  #: order of the error estimator (0: none, fixed step)
    new_evals: int  #: rhs evaluations per step given f0, f_new included
    dense_evals: int  #: extra rhs evaluations to prepare the dense output
    dense_rows: int  #: rows of the dense-output coefficients used by the interpolant
    stepper: str  #: template function of :mod:`.steppers` that takes one step
    dense: str  #: template function of :mod:`.steppers` that prepares the dense output
    error: str  #: kernel of :mod:`.errors` (generic tableau steps)
    controller: str  #: kernel of :mod:`.controllers`
    tableau: str  #: prefix of the tableau arrays here (generic tableau steps), or ""

    @property
    def adaptive(self) -> bool:
        return self.error_order > 0


MAX_STAGES = 16  #: rows of the stage workspace K
MAX_DENSE = 8  #: rows of the dense-output coefficient array Q

# ------------------------------------------------------- step-size control
SAFETY = 0.9  #: safety factor of all three controllers
DOPRI5_BETA = 0.04  #: Hairer's PI stabilisation (dopri5, BETA)
DOPRI5_EXPONENT = 0.2 - 0.75 * DOPRI5_BETA  #: dopri5 EXPO1
DOPRI5_MIN_FACTOR = 0.2
DOPRI5_MAX_FACTOR = 10.0
DOP853_EXPONENT = 1.0 / 8.0
DOP853_MIN_FACTOR = 1.0 / 3.0
DOP853_MAX_FACTOR = 6.0
CASH_KARP_PGROW = -0.2  #: Numerical Recipes rkqs
CASH_KARP_PSHRNK = -0.25
CASH_KARP_ERRCON = 1.89e-4  #: (5 / SAFETY) ** (1 / PGROW)
CASH_KARP_MAX_FACTOR = 5.0
CASH_KARP_MIN_FACTOR = 0.1
CASH_KARP_TINY = 1.0e-30
ERR_FLOOR = 1.0e-4  #: floor of the previous error in the PI controller (dopri5 FACOLD)

# ----------------------------------------------------- Dormand-Prince 5(4)
# Dormand & Prince (1980); rows/columns as in scipy.integrate.RK45. The tableau
# (c, A, b, e) is written out as scalars before :func:`dopri5_step`.
#: Shampine's 4th-order continuous extension (scipy RK45.P, Hairer dopri5 D1..D7)
DOPRI5_P = np.array([
    [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933,
     87487479700 / 32700410799],
    [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408,
     701980252875 / 199316789632],
    [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])
#: weights of the quartic row F_3 of the nested form; the same polynomial as P
DOPRI5_DENSE = DOPRI5_P[:, 3].copy()

# ------------------------------------------------------------ Cash-Karp 5(4)
# Cash & Karp (1990), Numerical Recipes 2nd ed. sec. 16.2 (rkck).
CASH_KARP_C = np.array([0.0, 1 / 5, 3 / 10, 3 / 5, 1.0, 7 / 8])
CASH_KARP_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0],
    [3 / 10, -9 / 10, 6 / 5, 0.0, 0.0, 0.0],
    [-11 / 54, 5 / 2, -70 / 27, 35 / 27, 0.0, 0.0],
    [1631 / 55296, 175 / 512, 575 / 13824, 44275 / 110592, 253 / 4096, 0.0],
])
#: 5th-order weights c_i (propagated)
CASH_KARP_B = np.array([37 / 378, 0.0, 250 / 621, 125 / 594, 0.0, 512 / 1771])
#: dc_i = c_i - c*_i (5th minus embedded 4th order); last entry: f_new (unused)
CASH_KARP_E = np.array([
    37 / 378 - 2825 / 27648,
    0.0,
    250 / 621 - 18575 / 48384,
    125 / 594 - 13525 / 55296,
    -277 / 14336,
    512 / 1771 - 1 / 4,
    0.0,
])

# ------------------------------------------------------------ classical RK4
RK4_C = np.array([0.0, 0.5, 0.5, 1.0])
RK4_A = np.array([
    [0.0, 0.0, 0.0, 0.0],
    [0.5, 0.0, 0.0, 0.0],
    [0.0, 0.5, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
])
RK4_B = np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6])

# --------------------------------------------------------- Dormand-Prince 8(5,3)
# Coefficients copied verbatim from scipy/integrate/_ivp/dop853_coefficients.py
# (SciPy, BSD 3-Clause licence, Copyright (c) 2001-2002 Enthought, Inc. and
# 2003- SciPy Developers), themselves from Hairer's dop853.f. Rows 0-11 of A
# are the 12 stages, row 12 the weights B, rows 13-15 the extra stages of the
# dense output; E5 and E3 are the 5th- and 3rd-order error weights (entry 12
# multiplies f_new), D the last four rows of the 7th-order interpolant.
DOP853_C = np.array([0.0,
                     0.526001519587677318785587544488e-01,
                     0.789002279381515978178381316732e-01,
                     0.118350341907227396726757197510,
                     0.281649658092772603273242802490,
                     0.333333333333333333333333333333,
                     0.25,
                     0.307692307692307692307692307692,
                     0.651282051282051282051282051282,
                     0.6,
                     0.857142857142857142857142857142,
                     1.0,
                     1.0,
                     0.1,
                     0.2,
                     0.777777777777777777777777777778])

DOP853_A = np.zeros((16, 16))
DOP853_A[1, 0] = 5.26001519587677318785587544488e-2

DOP853_A[2, 0] = 1.97250569845378994544595329183e-2
DOP853_A[2, 1] = 5.91751709536136983633785987549e-2

DOP853_A[3, 0] = 2.95875854768068491816892993775e-2
DOP853_A[3, 2] = 8.87627564304205475450678981324e-2

DOP853_A[4, 0] = 2.41365134159266685502369798665e-1
DOP853_A[4, 2] = -8.84549479328286085344864962717e-1
DOP853_A[4, 3] = 9.24834003261792003115737966543e-1

DOP853_A[5, 0] = 3.7037037037037037037037037037e-2
DOP853_A[5, 3] = 1.70828608729473871279604482173e-1
DOP853_A[5, 4] = 1.25467687566822425016691814123e-1

DOP853_A[6, 0] = 3.7109375e-2
DOP853_A[6, 3] = 1.70252211019544039314978060272e-1
DOP853_A[6, 4] = 6.02165389804559606850219397283e-2
DOP853_A[6, 5] = -1.7578125e-2

DOP853_A[7, 0] = 3.70920001185047927108779319836e-2
DOP853_A[7, 3] = 1.70383925712239993810214054705e-1
DOP853_A[7, 4] = 1.07262030446373284651809199168e-1
DOP853_A[7, 5] = -1.53194377486244017527936158236e-2
DOP853_A[7, 6] = 8.27378916381402288758473766002e-3

DOP853_A[8, 0] = 6.24110958716075717114429577812e-1
DOP853_A[8, 3] = -3.36089262944694129406857109825
DOP853_A[8, 4] = -8.68219346841726006818189891453e-1
DOP853_A[8, 5] = 2.75920996994467083049415600797e1
DOP853_A[8, 6] = 2.01540675504778934086186788979e1
DOP853_A[8, 7] = -4.34898841810699588477366255144e1

DOP853_A[9, 0] = 4.77662536438264365890433908527e-1
DOP853_A[9, 3] = -2.48811461997166764192642586468
DOP853_A[9, 4] = -5.90290826836842996371446475743e-1
DOP853_A[9, 5] = 2.12300514481811942347288949897e1
DOP853_A[9, 6] = 1.52792336328824235832596922938e1
DOP853_A[9, 7] = -3.32882109689848629194453265587e1
DOP853_A[9, 8] = -2.03312017085086261358222928593e-2

DOP853_A[10, 0] = -9.3714243008598732571704021658e-1
DOP853_A[10, 3] = 5.18637242884406370830023853209
DOP853_A[10, 4] = 1.09143734899672957818500254654
DOP853_A[10, 5] = -8.14978701074692612513997267357
DOP853_A[10, 6] = -1.85200656599969598641566180701e1
DOP853_A[10, 7] = 2.27394870993505042818970056734e1
DOP853_A[10, 8] = 2.49360555267965238987089396762
DOP853_A[10, 9] = -3.0467644718982195003823669022

DOP853_A[11, 0] = 2.27331014751653820792359768449
DOP853_A[11, 3] = -1.05344954667372501984066689879e1
DOP853_A[11, 4] = -2.00087205822486249909675718444
DOP853_A[11, 5] = -1.79589318631187989172765950534e1
DOP853_A[11, 6] = 2.79488845294199600508499808837e1
DOP853_A[11, 7] = -2.85899827713502369474065508674
DOP853_A[11, 8] = -8.87285693353062954433549289258
DOP853_A[11, 9] = 1.23605671757943030647266201528e1
DOP853_A[11, 10] = 6.43392746015763530355970484046e-1

DOP853_A[12, 0] = 5.42937341165687622380535766363e-2
DOP853_A[12, 5] = 4.45031289275240888144113950566
DOP853_A[12, 6] = 1.89151789931450038304281599044
DOP853_A[12, 7] = -5.8012039600105847814672114227
DOP853_A[12, 8] = 3.1116436695781989440891606237e-1
DOP853_A[12, 9] = -1.52160949662516078556178806805e-1
DOP853_A[12, 10] = 2.01365400804030348374776537501e-1
DOP853_A[12, 11] = 4.47106157277725905176885569043e-2

DOP853_A[13, 0] = 5.61675022830479523392909219681e-2
DOP853_A[13, 6] = 2.53500210216624811088794765333e-1
DOP853_A[13, 7] = -2.46239037470802489917441475441e-1
DOP853_A[13, 8] = -1.24191423263816360469010140626e-1
DOP853_A[13, 9] = 1.5329179827876569731206322685e-1
DOP853_A[13, 10] = 8.20105229563468988491666602057e-3
DOP853_A[13, 11] = 7.56789766054569976138603589584e-3
DOP853_A[13, 12] = -8.298e-3

DOP853_A[14, 0] = 3.18346481635021405060768473261e-2
DOP853_A[14, 5] = 2.83009096723667755288322961402e-2
DOP853_A[14, 6] = 5.35419883074385676223797384372e-2
DOP853_A[14, 7] = -5.49237485713909884646569340306e-2
DOP853_A[14, 10] = -1.08347328697249322858509316994e-4
DOP853_A[14, 11] = 3.82571090835658412954920192323e-4
DOP853_A[14, 12] = -3.40465008687404560802977114492e-4
DOP853_A[14, 13] = 1.41312443674632500278074618366e-1

DOP853_A[15, 0] = -4.28896301583791923408573538692e-1
DOP853_A[15, 5] = -4.69762141536116384314449447206
DOP853_A[15, 6] = 7.68342119606259904184240953878
DOP853_A[15, 7] = 4.06898981839711007970213554331
DOP853_A[15, 8] = 3.56727187455281109270669543021e-1
DOP853_A[15, 12] = -1.39902416515901462129418009734e-3
DOP853_A[15, 13] = 2.9475147891527723389556272149
DOP853_A[15, 14] = -9.15095847217987001081870187138


DOP853_B = DOP853_A[12, :12].copy()

DOP853_E3 = np.zeros(13)
DOP853_E3[:-1] = DOP853_B
DOP853_E3[0] -= 0.244094488188976377952755905512
DOP853_E3[8] -= 0.733846688281611857341361741547
DOP853_E3[11] -= 0.220588235294117647058823529412e-1

DOP853_E5 = np.zeros(13)
DOP853_E5[0] = 0.1312004499419488073250102996e-1
DOP853_E5[5] = -0.1225156446376204440720569753e+1
DOP853_E5[6] = -0.4957589496572501915214079952
DOP853_E5[7] = 0.1664377182454986536961530415e+1
DOP853_E5[8] = -0.3503288487499736816886487290
DOP853_E5[9] = 0.3341791187130174790297318841
DOP853_E5[10] = 0.8192320648511571246570742613e-1
DOP853_E5[11] = -0.2235530786388629525884427845e-1

# The first 3 rows of the interpolant are built from y, y_new, f0, f_new.
DOP853_D = np.zeros((4, 16))
DOP853_D[0, 0] = -0.84289382761090128651353491142e+1
DOP853_D[0, 5] = 0.56671495351937776962531783590
DOP853_D[0, 6] = -0.30689499459498916912797304727e+1
DOP853_D[0, 7] = 0.23846676565120698287728149680e+1
DOP853_D[0, 8] = 0.21170345824450282767155149946e+1
DOP853_D[0, 9] = -0.87139158377797299206789907490
DOP853_D[0, 10] = 0.22404374302607882758541771650e+1
DOP853_D[0, 11] = 0.63157877876946881815570249290
DOP853_D[0, 12] = -0.88990336451333310820698117400e-1
DOP853_D[0, 13] = 0.18148505520854727256656404962e+2
DOP853_D[0, 14] = -0.91946323924783554000451984436e+1
DOP853_D[0, 15] = -0.44360363875948939664310572000e+1

DOP853_D[1, 0] = 0.10427508642579134603413151009e+2
DOP853_D[1, 5] = 0.24228349177525818288430175319e+3
DOP853_D[1, 6] = 0.16520045171727028198505394887e+3
DOP853_D[1, 7] = -0.37454675472269020279518312152e+3
DOP853_D[1, 8] = -0.22113666853125306036270938578e+2
DOP853_D[1, 9] = 0.77334326684722638389603898808e+1
DOP853_D[1, 10] = -0.30674084731089398182061213626e+2
DOP853_D[1, 11] = -0.93321305264302278729567221706e+1
DOP853_D[1, 12] = 0.15697238121770843886131091075e+2
DOP853_D[1, 13] = -0.31139403219565177677282850411e+2
DOP853_D[1, 14] = -0.93529243588444783865713862664e+1
DOP853_D[1, 15] = 0.35816841486394083752465898540e+2

DOP853_D[2, 0] = 0.19985053242002433820987653617e+2
DOP853_D[2, 5] = -0.38703730874935176555105901742e+3
DOP853_D[2, 6] = -0.18917813819516756882830838328e+3
DOP853_D[2, 7] = 0.52780815920542364900561016686e+3
DOP853_D[2, 8] = -0.11573902539959630126141871134e+2
DOP853_D[2, 9] = 0.68812326946963000169666922661e+1
DOP853_D[2, 10] = -0.10006050966910838403183860980e+1
DOP853_D[2, 11] = 0.77771377980534432092869265740
DOP853_D[2, 12] = -0.27782057523535084065932004339e+1
DOP853_D[2, 13] = -0.60196695231264120758267380846e+2
DOP853_D[2, 14] = 0.84320405506677161018159903784e+2
DOP853_D[2, 15] = 0.11992291136182789328035130030e+2

DOP853_D[3, 0] = -0.25693933462703749003312586129e+2
DOP853_D[3, 5] = -0.15418974869023643374053993627e+3
DOP853_D[3, 6] = -0.23152937917604549567536039109e+3
DOP853_D[3, 7] = 0.35763911791061412378285349910e+3
DOP853_D[3, 8] = 0.93405324183624310003907691704e+2
DOP853_D[3, 9] = -0.37458323136451633156875139351e+2
DOP853_D[3, 10] = 0.10409964950896230045147246184e+3
DOP853_D[3, 11] = 0.29840293426660503123344363579e+2
DOP853_D[3, 12] = -0.43533456590011143754432175058e+2
DOP853_D[3, 13] = 0.96324553959188282948394950600e+2
DOP853_D[3, 14] = -0.39177261675615439165231486172e+2
DOP853_D[3, 15] = -0.14972683625798562581422125276e+3


# Dormand-Prince coefficients as scalars: the default method's step is unrolled
# (compile-time constants, one pass over the state per stage, no zero tests).
_A21 = 1 / 5
_A31, _A32 = 3 / 40, 9 / 40
_A41, _A42, _A43 = 44 / 45, -56 / 15, 32 / 9
_A51, _A52, _A53, _A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
_A61, _A62, _A63, _A64, _A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
_B1, _B3, _B4, _B5, _B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
_E1, _E3, _E4, _E5, _E6, _E7 = (-71 / 57600, 71 / 16695, -71 / 1920, 17253 / 339200,
                                -22 / 525, 1 / 40)




DOPRI5 = Method("dopri5", 5, 4, 6, 0, 4, "dopri5_step", "dopri5_dense", "", "pi_factor", "")
CASH_KARP = Method("cash-karp", 5, 4, 6, 0, 3, "tableau_step", "hermite_dense",
                   "cash_karp_error", "rkqs_factor", "CASH_KARP")
RK4 = Method("rk4", 4, 0, 4, 0, 3, "tableau_step", "hermite_dense", "no_error",
             "fixed_factor", "RK4")
DOP853 = Method("dop853", 8, 7, 12, 3, 7, "tableau_step", "dop853_dense", "dop853_error",
                "dop853_factor", "DOP853")
METHODS = {m.name: m for m in (DOPRI5, CASH_KARP, RK4, DOP853)}  #: by name
METHOD_NAMES = tuple(METHODS)
