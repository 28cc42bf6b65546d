//! Chegodaeva (2004): symplectic integration of small Solar System bodies.

pub mod comet_population;
pub mod symplectic_100myr;
pub mod symplectic_order;
