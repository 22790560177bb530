# Linear Reissner-Mindlin flat-facet shell (dembridge).
#
# Unknowns per node, all in the global frame: 3 translations u and 3 rotations
# theta (rotation vector). Through the thickness, U(z) = u + z (theta x n), the
# kinematics of the paper's equation [6]. Each cell uses its own flat frame
# (t1, t2, n) built from the Jacobian, so the same file serves shells placed
# anywhere in space.
#
# Energy density per unit mid-surface area, multiplied by the weight field eta
# (1 everywhere by default; the bridging-domain coupling sets it):
#   membrane  h     C : eps(u) : eps(u) / 2
#   bending   h^3/12 C : kappa   : kappa  / 2,  kappa = sym grad_s(theta x n)
#   shear     k G h |gamma|^2 / 2,  gamma = grad_s(u.n) + (theta x n)
#   drilling  c_d G h (theta.n - omega(u))^2 / 2, omega the in-plane rotation
# C is the plane-stress elasticity tensor. Reinforced-concrete sections add
# their steel layers, smeared over the width (per cell, zero for plain
# concrete): a layer of bars along the in-plane direction d, area a per unit
# width at height z along n, has the strain eps_d + z kappa_d
# (eps_d = d.eps.d, kappa_d = d.kappa.d) and adds, with E' = E_s - E (the
# transformed section: the bars take the place of concrete),
#   steel     E' (a eps_d^2 + 2 a z eps_d kappa_d + a z^2 kappa_d^2) / 2.
# Summed over the layers of one direction, only the sums A = sum a,
# S = sum a z and I = sum a z^2 enter, times E'. Transverse shear is locking-free:
#   quadrilaterals: selective reduced integration (shear at one point);
#   triangles: discrete shear gap (DSG3, Bletzinger et al. 2000), tied on the
#     edges, averaged over the three choices of corner node so the result does
#     not depend on the node numbering, evaluated at the centroid.
#
# The build compiles this file once per cell type: it rewrites the CELL line.
# Material and geometry are run-time Constants (set from C++).
import ufl
from ufl import (Cell, Coefficient, Constant, FiniteElement, FunctionSpace,
                 Jacobian, Mesh, TestFunction, TrialFunction, VectorElement,
                 as_matrix, as_vector, cross, derivative, dot, inner, sqrt, tr,
                 Identity)

CELL = "quadrilateral"  # dembridge:cell

cell = Cell(CELL, geometric_dimension=3)
mesh = Mesh(VectorElement("Lagrange", cell, 1))
V = FunctionSpace(mesh, VectorElement("Lagrange", cell, 1, dim=6))
W = FunctionSpace(mesh, FiniteElement("Lagrange", cell, 1))

E = Constant(mesh)         # Young's modulus [Pa]
nu = Constant(mesh)        # Poisson's ratio [-]
rho = Constant(mesh)       # density [kg/m^3]
h = Constant(mesh)         # thickness [m]
k_shear = Constant(mesh)   # shear correction factor [-] (5/6)
c_drill = Constant(mesh)   # drilling penalty, fraction of G h [-]
eta = Coefficient(W)       # energy weight [-]
# Smeared reinforcement per cell (DG0, all zero for plain concrete):
#  [0:3]  E' (A, S, I) of the bars along d1 [N/m, N, N m]
#  [3:6]  E' (A, S, I) of the bars along d2 = n x d1
#  [6:8]  (rho_s - rho) (A1 + A2), (rho_s - rho) (I1 + I2) [kg/m^2, kg]
#  [8:11] a global vector whose projection on the cell's plane is d1
steel = Coefficient(FunctionSpace(mesh, VectorElement("DG", cell, 0, dim=11)))

U = Coefficient(V)         # state at which residuals are evaluated
v = TestFunction(V)
du = TrialFunction(V)

G = E / (2 * (1 + nu))

# Cell frame from the Jacobian (3 x 2 on a manifold cell).
J = Jacobian(mesh)
j0 = as_vector([J[i, 0] for i in range(3)])
j1 = as_vector([J[i, 1] for i in range(3)])
nn = cross(j0, j1)
n = nn / sqrt(dot(nn, nn))
t1 = j0 / sqrt(dot(j0, j0))
t2 = cross(n, t1)
P = as_matrix([[t1[i] for i in range(3)], [t2[i] for i in range(3)]])  # 2 x 3


def parts(w):
    return as_vector([w[i] for i in range(3)]), as_vector([w[i] for i in range(3, 6)])


def grad_cross_n(Gt):
    """Tangential gradient of theta x n for a cell-wise constant n: Gt = grad(theta)."""
    return as_matrix([[sum(ufl.classes.PermutationSymbol(3)[i, j, k] * Gt[j, l] * n[k]
                           for j in range(3) for k in range(3))
                       for l in range(3)] for i in range(3)])


def sym2(A):
    return 0.5 * (A + A.T)


def plane_stress(e):
    return E / (1 - nu**2) * ((1 - nu) * e + nu * tr(e) * Identity(2))


u, theta = parts(U)
Gu = ufl.grad(u)            # 3 x 3 tangential gradient
Gt = ufl.grad(theta)
eps = sym2(P * Gu * P.T)
kappa = sym2(P * grad_cross_n(Gt) * P.T)
omega = 0.5 * (dot(t2, Gu * t1) - dot(t1, Gu * t2))
grad_w = Gu.T * n           # tangential gradient of u.n (n constant per cell)

# The bars' directions in the cell frame: d1 the projection of the given
# vector, d2 normal to it in the plane (d1, d2, n right-handed). A plain cell
# has a zero vector: the tiny term keeps d1 = 0 there instead of 0/0.
d1p = P * as_vector([steel[8], steel[9], steel[10]])
d1 = d1p / sqrt(dot(d1p, d1p) + 1e-300)
d2 = as_vector([-d1[1], d1[0]])


def steel_energy(d, k):
    e_d, k_d = dot(d, eps * d), dot(d, kappa * d)
    return 0.5 * (steel[k] * e_d**2 + 2 * steel[k + 1] * e_d * k_d + steel[k + 2] * k_d**2)


if CELL == "triangle":
    # DSG3: the covariant shear strain along an edge of vector a (corner k to
    # node i) is the shear gap grad(w).a + (theta(m) x n).a with theta at the
    # edge mid-point m (exact for linear fields). Two edges from one corner fix
    # a constant strain; average the three corners. Evaluated at the centroid.
    ref = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
    c = (1.0 / 3.0, 1.0 / 3.0)

    def edge_vector(d):
        return d[0] * j0 + d[1] * j1

    gam = 0
    for k in range(3):
        others = [i for i in range(3) if i != k]
        vecs, covs = [], []
        for i in others:
            a = edge_vector((ref[i][0] - ref[k][0], ref[i][1] - ref[k][1]))
            dm = edge_vector((0.5 * (ref[i][0] + ref[k][0]) - c[0],
                              0.5 * (ref[i][1] + ref[k][1]) - c[1]))
            theta_m = theta + Gt * dm
            vecs.append(a)
            covs.append(dot(grad_w, a) + dot(cross(theta_m, n), a))
        a, b = vecs
        gaa, gab, gbb = dot(a, a), dot(a, b), dot(b, b)
        det = gaa * gbb - gab * gab
        dual_a = (gbb * a - gab * b) / det
        dual_b = (gaa * b - gab * a) / det
        gam = gam + (covs[0] * dual_a + covs[1] * dual_b) / 3.0
    shear_degree = 1
else:
    gam = grad_w + cross(theta, n)
    shear_degree = 1   # one Gauss point on quadrilaterals: selective reduced

dx_full = ufl.dx(metadata={"quadrature_degree": 2})
dx_shear = ufl.dx(metadata={"quadrature_degree": shear_degree})

psi_full = 0.5 * h * inner(plane_stress(eps), eps) \
    + 0.5 * h**3 / 12 * inner(plane_stress(kappa), kappa) \
    + 0.5 * c_drill * G * h * (dot(theta, n) - omega)**2 \
    + steel_energy(d1, 0) + steel_energy(d2, 3)
psi_shear = 0.5 * k_shear * G * h * dot(gam, gam)

Pi = eta * psi_full * dx_full + eta * psi_shear * dx_shear

# Residual (internal forces) and its Jacobian (the stiffness).
F = derivative(Pi, U, v)
a = derivative(F, U, du)

# Row sums of the consistent mass: lumped mass with rotary inertia rho h^3/12,
# plus the bars' (their first moment, a coupling of translations and
# rotations, has no row sum and is left out, as usual with lumped masses).
vu, vt = parts(v)
m_lumped = ((rho * h + steel[6]) * (vu[0] + vu[1] + vu[2])
            + (rho * h**3 / 12 + steel[7]) * (vt[0] + vt[1] + vt[2])) * dx_full

# Tributary mid-surface area of each node (on its first dof).
measure = vu[0] * dx_full

# The section's stresses, averaged over each cell (the output's; no energy
# weight: they are the physical ones), in the global frame: the concrete's
# plane stresses at the +n face, C (eps + h/2 kappa), and at the -n face,
# C (eps - h/2 kappa), the membrane forces h C eps [N/m] and the bending
# moments h^3/12 C kappa [N m/m], each the 3 x 3 tensor P^T s P; last the
# cell's area, which divides them. The bars' share is not in them.
Qs = FunctionSpace(mesh, VectorElement("DG", cell, 0, dim=37))
q = TestFunction(Qs)


def global_frame(s2):
    return P.T * s2 * P


section_parts = [global_frame(plane_stress(eps + 0.5 * h * kappa)),
                 global_frame(plane_stress(eps - 0.5 * h * kappa)),
                 global_frame(h * plane_stress(eps)),
                 global_frame(h**3 / 12 * plane_stress(kappa))]
section_values = [t[i, j] for t in section_parts for i in range(3) for j in range(3)] + [1.0]
sections = dot(as_vector(section_values), q) * dx_full

forms = [a, F, m_lumped, measure, sections]
