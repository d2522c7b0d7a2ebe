"""Labels of the RK4 map: which attractor an orbit reaches, certified by the energy trap.

:mod:`~atlas.labels.labelling` (:func:`atlas.label`), :mod:`~atlas.labels.trap` (the energy
trap's level), :mod:`~atlas.labels.methods` (the discretisations) and
:mod:`~atlas.labels.backends` (the devices).
"""
