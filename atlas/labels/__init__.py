"""Labels of the RK4 map: which attractor an orbit reaches, certified by the energy trap."""
