//! Neighbour search (work in progress).
