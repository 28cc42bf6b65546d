//! Chegodaeva (2004), symplectic integration of the equations of motion of small Solar
//! System bodies (crate `symplectic`): the paper's 100 Myr experiment, the maps' order,
//! populations of comets on their own clocks, and comets through close encounters.

pub mod centaur_population;
mod centaur_sample;
pub mod comet_encounters;
pub mod comet_population;
pub mod symplectic_100myr;
pub mod symplectic_order;
