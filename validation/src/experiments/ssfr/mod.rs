//! Screen-space fluid rendering (Im & Chan 2016, §IV; van der Laan, Green & Sainz 2009):
//! the accuracy of the smoothed depth and normals against analytic surfaces, the paper's
//! refraction against the exact refracted ray, and the cost per stage.

pub mod shapes;
pub mod ssfr_depth_accuracy;
pub mod ssfr_performance;
pub mod ssfr_refraction;
