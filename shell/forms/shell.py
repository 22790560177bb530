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
# C is the plane-stress elasticity tensor. Transverse shear is locking-free:
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
    + 0.5 * c_drill * G * h * (dot(theta, n) - omega)**2
psi_shear = 0.5 * k_shear * G * h * dot(gam, gam)

Pi = eta * psi_full * dx_full + eta * psi_shear * dx_shear

# Residual (internal forces) and its Jacobian (the stiffness).
F = derivative(Pi, U, v)
a = derivative(F, U, du)

# Row sums of the consistent mass: lumped mass with rotary inertia rho h^3/12.
vu, vt = parts(v)
m_lumped = (rho * h * (vu[0] + vu[1] + vu[2])
            + rho * h**3 / 12 * (vt[0] + vt[1] + vt[2])) * dx_full

forms = [a, F, m_lumped]
