//! Integrators: Park's implicit method (variable step, Newton iterations,
//! Lagrange multipliers for cut joints) and the classical fixed-step RK4.
