"""How the robot equation is computed: the Lagrange-Euler reference and the fast kernels."""
