//! Im & Chan (2016), "SPH neighbour searching and screen space fluid rendering for unlimited
//! scenes" (crates `neighbour-search`, `ssfr-render`): the particle–cell relation table
//! against the plain cell grid (§III; Green 2008), and screen-space fluid rendering (§IV;
//! van der Laan, Green & Sainz 2009): the accuracy of the smoothed depth and normals against
//! analytic surfaces, the paper's refraction against the exact refracted ray, and the cost
//! per stage.

pub mod neighbour_search;
pub mod shapes;
pub mod ssfr_depth_accuracy;
pub mod ssfr_performance;
pub mod ssfr_refraction;
