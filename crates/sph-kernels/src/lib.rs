//! SPH smoothing kernels (work in progress).
