//! Chegodaeva (2004), symplectic integration of the equations of motion of small Solar
//! System bodies (crate `symplectic`): the paper's 100 Myr experiment, the maps' order, and
//! populations of comets on their own clocks.

pub mod comet_population;
pub mod symplectic_100myr;
pub mod symplectic_order;
