"""Physics of eq. (1): the pendulum, its critical points, closed forms, the running cycle."""
