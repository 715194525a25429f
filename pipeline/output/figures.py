"""The figures of one run now live in ``gyrolab.figures.run`` (one module per dataset kind); kept for imports."""

from gyrolab.figures.run import FIGURES, draw_body_axis, draw_euler_angles, draw_invariants, draw_state, save_figures

plot_state = draw_state
plot_invariants = draw_invariants
plot_euler_angles = draw_euler_angles
plot_body_axis = draw_body_axis
PLOTS = FIGURES

__all__ = ["FIGURES", "PLOTS", "draw_body_axis", "draw_euler_angles", "draw_invariants", "draw_state",
           "plot_body_axis", "plot_euler_angles", "plot_invariants", "plot_state", "save_figures"]
