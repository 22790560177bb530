# Linear elasticity on 3D solid cells (dembridge), P1 displacements.
#
# Energy density eta * (lambda/2 tr(eps)^2 + mu eps:eps), eta the energy weight
# of the bridging-domain coupling (1 by default). The build compiles this file
# once per cell type (hexahedron, tetrahedron): it rewrites the CELL line.
import ufl
from ufl import (Coefficient, Constant, FiniteElement, FunctionSpace, Mesh,
                 TestFunction, TrialFunction, VectorElement, derivative, inner,
                 sym, tr)

CELL = "hexahedron"  # dembridge:cell

mesh = Mesh(VectorElement("Lagrange", CELL, 1))
V = FunctionSpace(mesh, VectorElement("Lagrange", CELL, 1))
W = FunctionSpace(mesh, FiniteElement("Lagrange", CELL, 1))

E = Constant(mesh)     # Young's modulus [Pa]
nu = Constant(mesh)    # Poisson's ratio [-]
rho = Constant(mesh)   # density [kg/m^3]
eta = Coefficient(W)   # energy weight [-]

U = Coefficient(V)
v = TestFunction(V)
du = TrialFunction(V)

mu = E / (2 * (1 + nu))
lmbda = E * nu / ((1 + nu) * (1 - 2 * nu))
eps = sym(ufl.grad(U))
dx = ufl.dx(metadata={"quadrature_degree": 2})

Pi = eta * (0.5 * lmbda * tr(eps)**2 + mu * inner(eps, eps)) * dx
F = derivative(Pi, U, v)
a = derivative(F, U, du)

# Row sums of the consistent mass (lumped mass).
m_lumped = rho * (v[0] + v[1] + v[2]) * dx

# Tributary volume of each node (on its first dof).
measure = v[0] * dx

forms = [a, F, m_lumped, measure]
