//! The SPH foundation: kernels (Müller et al. 2003; Monaghan 1992; Wendland 1995) and the
//! neighbour search (Im & Chan 2016; Green 2008).

pub mod kernels;
pub mod neighbour_search;
