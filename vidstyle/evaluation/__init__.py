"""Evaluation harnesses: the protocols that score vidstyle's components (recognition, style, motion,
pose, AugMG, real-mocap diagnostics) against ground truth. They sit at the edge of the package, beside
the demo generator whose truth they read; the components they score never import them."""
