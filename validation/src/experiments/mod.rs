//! The experiments, one module each.

use crate::Experiment;

pub mod kernels;
pub mod neighbour_search;
pub mod symplectic_100myr;
pub mod symplectic_order;

/// Every registered experiment, in run order.
pub fn registry() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(kernels::Kernels),
        Box::new(neighbour_search::NeighbourSearchExperiment),
        Box::new(symplectic_100myr::Symplectic100Myr),
        Box::new(symplectic_order::SymplecticOrder),
    ]
}
