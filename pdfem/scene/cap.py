"""The Sandler-Rubin cap's scene keys and the rules that tie them together: one home for the
scene check (pdfem.scene.validate), the material table (pdfem.build) and the material-point
driver (pdfem.material_point). The kernel's check of a whole parameter row is
pdfem.kernels.cap.cap_check_params."""

import math

from pdfem.kernels import params as P
from pdfem.scene.values import show

# [materials.NAME] key of the cap model -> its parameter column (pdfem.kernels.params)
CAP_COLUMNS = {"A": P.CAP_A, "B": P.CAP_B, "C": P.CAP_C, "D": P.CAP_D, "R": P.CAP_R,
               "W": P.CAP_W, "kappa0": P.CAP_KAPPA0, "tension_cutoff": P.CAP_T,
               "tol": P.CAP_TOL, "relaxation_time": P.CAP_TAU}
# The keys a cap table may leave out: the cut-off defaults to the envelope's apex
# (envelope_apex), the tolerance to the kernel's, the relaxation time to 0 (rate-independent)
CAP_OPTIONAL = ("tension_cutoff", "tol", "relaxation_time")


def envelope_apex(a, b, c):
    """I1 where the failure envelope A - C exp(B I1) meets the axis in tension, ln(A/C)/B
    (B, C > 0; else 0): the default tension cut-off."""
    return math.log(a / c) / b if b > 0.0 and c > 0.0 else 0.0


def strength_rule(a, c):
    """'' when the envelope's constants are ordered (C < A: a positive strength at I1 = 0),
    else the reason, naming C."""
    return "" if c < a else f"must be < A = {show(float(a))} (got {show(float(c))})"
