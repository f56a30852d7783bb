"""Column layout of the material parameter table ``mat_params[mat_id, :]`` (float64, SI).

Kernels receive one row ``p = mat_params[m]`` and index it with these constants, so no
Python object ever reaches a kernel. Sign convention everywhere: tension positive,
compression negative; stress components are ordered (xx, yy, xy, zz).
"""

NPAR = 32

# Material model ids (column MODEL)
ELASTIC = 0
CAP = 1

MODEL = 0  # model id (float-coded int)
RHO = 1  # density [kg/m^3]
BULK = 2  # bulk modulus K [Pa]
SHEAR = 3  # shear modulus G [Pa]

# Sandler-Rubin cap model (compression negative, I1 = tr(sigma) in Pa)
CAP_A = 4  # failure envelope constant A [Pa]
CAP_B = 5  # failure envelope exponent B [1/Pa]
CAP_C = 6  # failure envelope constant C [Pa]
CAP_D = 7  # hardening rate D [1/Pa]
CAP_R = 8  # cap aspect ratio R [-]
CAP_W = 9  # maximum plastic volumetric compaction W [-]
CAP_KAPPA0 = 10  # initial cap position kappa_0 (I1 where cap meets envelope) [Pa]
CAP_T = 11  # tension cut-off on I1 (>= 0) [Pa]
CAP_TOL = 12  # yield-surface tolerance (relative) [-]
CAP_TAU = 13  # Duvaut-Lions relaxation time of the overstress; 0: rate-independent [s]

# Heat
ALPHA = 16  # linear thermal expansion coefficient [1/K]
CP = 17  # specific heat [J/(kg K)]
COND = 18  # thermal conductivity [W/(m K)]
BETA = 19  # fraction of plastic work turned into heat [-]
T_REF = 20  # reference temperature [K]
SOFT_K = 21  # moduli softening per kelvin: K(T) = K (1 - SOFT_K (T - T_REF)) [1/K]
SOFT_Y = 22  # strength softening per kelvin (scales A, C) [1/K]

# Equation of state (pdfem.kernels.eos)
EOS_S = 23  # slope s of the linear Us-up Hugoniot of the bulk response; 0: linear bulk [-]
EOS_G = 24  # Gruneisen coefficient Gamma0 (Gamma rho = Gamma0 rho0) on that Hugoniot; 0: none [-]
