"""The periodically driven damped pendulum, θ̈ + 2αθ̇ + ω0² sin θ = τ + A cos(Ω t + φ): its
basins are those of the stroboscopic map over one drive period, and its attractors are
found, not assumed. Description: :mod:`~atlas.models.driven.description`; planner:
:mod:`~atlas.models.driven.plan`."""
