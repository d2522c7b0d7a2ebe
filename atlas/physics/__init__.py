"""Physics of eq. (1) with torque: the pendulum (θ*, the vector field, energies, critical
points), its closed forms, the running limit cycle and its barrier."""
