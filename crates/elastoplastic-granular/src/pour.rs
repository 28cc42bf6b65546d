//! Grains poured during a run: a heap formed as the funnel method forms it (a funnel held
//! just above the growing heap's top, e.g. ISO 4324:1977 and ASTM C1444-00), a layer of
//! grains at a time. The pour is scene vocabulary (`sph_solver::scene_boundary::Pour`) and
//! its emitter is stepped by the frame shell (`sph_solver::scene_boundary::PourEmitter`);
//! this solver starts the poured grains unstressed.
//!
//! Why a pour: a heap formed by pouring grows by surface avalanches that stop at its toe
//! (in compression), where a drained heap's flanks form while they flow out (in extension);
//! with a Drucker–Prager cone the two stand at different angles
//! (`docs/elastoplastic-granular.md`, "Walls, moving walls, periodic axes and the pour").

pub use sph_solver::scene_boundary::{
    PeriodicAxis, Pour, PourEmitter, FALL_OVER_LANDING_TIME, MAX_POURED_GRAINS, ROOM_OVER_SPACING,
};
