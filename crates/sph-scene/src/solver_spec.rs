//! The solvers a scene can ask for, registered with one line each in [`solvers!`]: the
//! solver's kind name (the `[solver]` table's `kind`) and its crate's settings struct (a
//! [`SolverSettings`]). From that line follow [`SolverKind`], [`SolverSpec`] (the `[solver]`
//! table as types), [`SolverParams`] (the parameters it makes, in precision `R`), the
//! reading of the table (`parse/solver.rs`), the parameters (`params.rs`) and, through
//! [`SolverParams::build`], the factory of `sph-sim` and the density kernel.

use serde::Deserialize;
use sph_core::Real;
use sph_solver::scene_boundary::{BoundaryFeatures, SceneBoundary};
use sph_solver::{
    Boundary, CommonParams, CommonSettings, FluidSolver, KernelKind, SceneValues, SolverError,
    SolverParameters, SolverSettings,
};

/// Defines the solver enums from one line per solver:
/// `Variant = "kind", settings::Type [flattened parts read first for their errors' lines];`.
macro_rules! solvers {
    ($(
        $(#[$doc:meta])*
        $Kind:ident = $name:literal, $Settings:path [$($Part:ty),*];
    )+) => {
        /// The settings struct of each solver (the variants of [`SolverSpec`]), owned by its
        /// crate and re-exported here.
        pub mod settings {
            $( pub use $Settings; )+
        }

        /// Which solver a scene is meant for: the tag (`kind`) of the `[solver]` table, and
        /// [`SolverSpec::kind`]. Code can name a solver without its settings with it (e.g.
        /// to run one scene with two solvers, [`SolverSpec::with_kind`]).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
        pub enum SolverKind {
            $( $(#[$doc])* #[serde(rename = $name)] $Kind, )+
        }

        impl SolverKind {
            /// Every solver, in registration order.
            pub const ALL: &'static [SolverKind] = &[$(SolverKind::$Kind),+];

            /// The name used in scene files (`kind = "…"`).
            pub fn name(self) -> &'static str {
                match self {
                    $( SolverKind::$Kind => $name, )+
                }
            }

            /// The density kernel of the solver.
            pub fn density_kernel(self) -> KernelKind {
                match self {
                    $( SolverKind::$Kind => <$Settings as SolverSettings>::DENSITY_KERNEL, )+
                }
            }

            /// The solver's name in reports (its settings' [`SolverSettings::LABEL`],
            /// the name the solver gives itself, e.g. `"PBF"`, `"IISPH-granular"`).
            pub fn label(self) -> &'static str {
                match self {
                    $( SolverKind::$Kind => <$Settings as SolverSettings>::LABEL, )+
                }
            }

            /// Whether the solver runs in the plane ([`SolverSettings::PLANAR`]).
            pub fn planar(self) -> bool {
                match self {
                    $( SolverKind::$Kind => <$Settings as SolverSettings>::PLANAR, )+
                }
            }

            /// The scene boundary features the solver takes
            /// ([`SolverSettings::BOUNDARY_FEATURES`]).
            pub fn boundary_features(self) -> BoundaryFeatures {
                match self {
                    $( SolverKind::$Kind => <$Settings as SolverSettings>::BOUNDARY_FEATURES, )+
                }
            }

            /// The keys renamed to their parameter's name: `(old key, key)`; a scene may
            /// write either.
            pub fn renamed(self) -> &'static [(&'static str, &'static str)] {
                match self {
                    $( SolverKind::$Kind => <$Settings as SolverSettings>::RENAMED, )+
                }
            }
        }

        /// Solver settings: the `[solver]` table, one variant per solver (its crate's
        /// settings struct), selected by `kind`; a key of another solver is refused (unknown
        /// field).
        ///
        /// Deserializes as an internally tagged table (`kind = "pbf"` + the settings). The
        /// scene parser reads `kind` first and then the settings from the same table, so
        /// that its errors keep the field path and line (see `parse/solver.rs`); both accept
        /// the same tables.
        #[derive(Debug, Clone, PartialEq, Deserialize)]
        #[serde(tag = "kind")]
        pub enum SolverSpec {
            $( $(#[$doc])* #[serde(rename = $name)] $Kind($Settings), )+
        }

        impl SolverSpec {
            /// Which solver.
            pub fn kind(&self) -> SolverKind {
                match self {
                    $( SolverSpec::$Kind(_) => SolverKind::$Kind, )+
                }
            }

            /// Settings for solver `kind` with `common`, every other setting the solver's
            /// default (`iterations` for a solver whose table requires a count).
            fn with_common(kind: SolverKind, common: CommonSettings, iterations: usize) -> Self {
                match kind {
                    $( SolverKind::$Kind => SolverSpec::$Kind(
                        <$Settings as SolverSettings>::with_common(common, iterations)
                    ), )+
                }
            }

            /// The settings every solver has.
            pub fn common(&self) -> &CommonSettings {
                match self {
                    $( SolverSpec::$Kind(s) => s.common(), )+
                }
            }

            /// The settings every solver has, to edit (check the scene again after, with
            /// [`Scene::check`](crate::Scene::check)).
            pub fn common_mut(&mut self) -> &mut CommonSettings {
                match self {
                    $( SolverSpec::$Kind(s) => s.common_mut(), )+
                }
            }

            /// The iterations per step (PBF: `solver_iterations`; PCISPH:
            /// `pressure_iterations`; the IISPH kinds: `max_iterations` or its default).
            pub fn iterations(&self) -> usize {
                match self {
                    $( SolverSpec::$Kind(s) => s.iterations(), )+
                }
            }

            /// Sets the iterations per step ([`SolverSpec::iterations`]); not range-checked
            /// ([`Scene::check`](crate::Scene::check) does).
            pub fn set_iterations(&mut self, n: usize) {
                match self {
                    $( SolverSpec::$Kind(s) => s.set_iterations(n), )+
                }
            }

            /// The fewest iterations per step the settings give, if the solver has such a
            /// bound.
            pub fn min_iterations(&self) -> Option<usize> {
                match self {
                    $( SolverSpec::$Kind(s) => s.min_iterations(), )+
                }
            }

            /// The parameters in `f64` (not validated).
            pub(crate) fn params(&self, scene: &SceneValues) -> SolverParams<f64> {
                match self {
                    $( SolverSpec::$Kind(s) => SolverParams::$Kind(s.params(scene)), )+
                }
            }

            /// The checks of the settings as written ([`SolverSettings::check_written`]).
            pub(crate) fn check_written(
                &self,
                key: &dyn Fn(&'static str) -> String,
            ) -> Result<(), (&'static str, String)> {
                match self {
                    $( SolverSpec::$Kind(s) => s.check_written(key), )+
                }
            }

            /// Reads the settings of `kind` with `read` (the variant, then its flattened
            /// parts first, [`SettingsReader`]).
            pub(crate) fn read<E>(
                kind: SolverKind,
                read: &mut impl SettingsReader<E>,
            ) -> Result<SolverSpec, E> {
                read.part::<CommonSettings>()?;
                Ok(match kind {
                    $( SolverKind::$Kind => {
                        $( read.part::<$Part>()?; )*
                        SolverSpec::$Kind(read.settings::<$Settings>()?)
                    } )+
                })
            }
        }

        /// The parameters of the solver a scene asks for, in precision `R`: one variant per
        /// solver kind, holding its crate's parameters.
        #[derive(Debug, Clone, PartialEq)]
        pub enum SolverParams<R: Real> {
            $( $(#[$doc])* $Kind(<$Settings as SolverSettings>::Params<R>), )+
        }

        impl<R: Real> SolverParams<R> {
            /// Which solver.
            pub fn kind(&self) -> SolverKind {
                match self {
                    $( SolverParams::$Kind(_) => SolverKind::$Kind, )+
                }
            }

            /// The parameters every solver has.
            pub fn common(&self) -> &CommonParams<R> {
                match self {
                    $( SolverParams::$Kind(p) => p.common(), )+
                }
            }

            /// The solver's own range checks (its parameters' `validate`).
            pub fn validate(&self) -> Result<(), SolverError> {
                match self {
                    $( SolverParams::$Kind(p) => SolverParameters::validate(p), )+
                }
            }

            /// The solver with these parameters and `boundary` (its constructor checks the
            /// parameters and that the boundary fits them): the workspace's one factory.
            pub fn build(
                self,
                boundary: Box<dyn Boundary<R>>,
            ) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
                match self {
                    $( SolverParams::$Kind(p) => <$Settings as SolverSettings>::build(p, boundary), )+
                }
            }
        }

        impl SolverParams<f64> {
            /// The parameters in precision `S` (each solver's `try_convert`: an error names a
            /// value that does not fit).
            pub fn try_convert<S: Real>(&self) -> Result<SolverParams<S>, SolverError> {
                Ok(match self {
                    $( SolverParams::$Kind(p) => SolverParams::$Kind(SolverParameters::convert::<S>(p)?), )+
                })
            }

            /// Takes the scene's boundary into the parameters
            /// ([`SolverSettings::take_scene_boundary`]: an error when the solver does not
            /// take a feature the boundary uses).
            pub(crate) fn take_scene_boundary(
                &mut self,
                boundary: SceneBoundary<f64>,
            ) -> Result<(), SolverError> {
                match self {
                    $( SolverParams::$Kind(p) => <$Settings as SolverSettings>::take_scene_boundary(p, boundary), )+
                }
            }

            /// The key of a refused parameter `name` (value `value`) that is not itself a key,
            /// with the value as that key states it ([`SolverSettings::key_of`]).
            pub(crate) fn key_of(&self, name: &str, value: f64) -> Option<(&'static str, f64)> {
                match self {
                    $( SolverParams::$Kind(p) => <$Settings as SolverSettings>::key_of(p, name, value), )+
                }
            }
        }
    };
}

/// Reads a solver's settings from a `[solver]` table (`parse/solver.rs`).
pub(crate) trait SettingsReader<E> {
    /// Reads a flattened part on its own (other keys ignored), for its errors only.
    fn part<T: serde::de::DeserializeOwned>(&mut self) -> Result<(), E>;
    /// Reads the whole settings.
    fn settings<T: serde::de::DeserializeOwned>(&mut self) -> Result<T, E>;
}

solvers! {
    /// Position Based Fluids (Macklin & Müller 2013), crate `pbf`.
    Pbf = "pbf", pbf::PbfSettings [];
    /// Predictive-corrective incompressible SPH (Solenthaler & Pajarola 2009), crate
    /// `pcisph`.
    Pcisph = "pcisph", pcisph::PcisphSettings [];
    /// Implicit incompressible SPH (Ihmsen et al. 2014) for water, crate `iisph-granular`.
    Iisph = "iisph", iisph_granular::WaterSettings [iisph_granular::IisphSettings];
    /// IISPH with Drucker–Prager friction, drag and upscaling for granular matter (Neder
    /// 2024), crate `iisph-granular`.
    Granular = "granular", iisph_granular::GranularSettings [iisph_granular::IisphSettings];
    /// Elastic–plastic Drucker–Prager SPH for granular matter (Bui, Fukagawa, Sako & Ohno
    /// 2008), crate `elastoplastic-granular`: walls of boundary particles
    /// (`[boundary] model = "particles"`).
    Elastoplastic = "elastoplastic", elastoplastic_granular::ElastoplasticSettings [];
}

impl SolverSpec {
    /// The solver's name in scene files (`"pbf"`, …).
    pub fn kind_name(&self) -> &'static str {
        self.kind().name()
    }

    /// Solver steps per frame.
    pub fn substeps(&self) -> usize {
        self.common().substeps
    }

    /// Passive points per particle (granular upscaling), `None` when off or not granular.
    pub fn upscaling_factor(&self) -> Option<usize> {
        match self {
            SolverSpec::Granular(g) => g.upscaling_factor,
            _ => None,
        }
    }

    /// The density kernel of the solver.
    pub fn density_kernel(&self) -> KernelKind {
        self.kind().density_kernel()
    }

    /// These settings for solver `kind`: a copy when `kind` is this solver's; otherwise the
    /// settings every solver has ([`CommonSettings`]) and the iteration count carried over
    /// (to a solver whose table requires one: PBF, PCISPH), with XSPH `c` between PBF and
    /// PCISPH and the [`iisph_granular::IisphSettings`] between `iisph` and `granular`, and
    /// the rest left to the other solver's defaults (a `granular` made from another kind
    /// gets `friction_angle_deg = 0`, i.e. no friction).
    pub fn with_kind(&self, kind: SolverKind) -> SolverSpec {
        if self.kind() == kind {
            return self.clone();
        }
        let mut to = SolverSpec::with_common(kind, self.common().clone(), self.iterations());
        match (self, &mut to) {
            (SolverSpec::Pbf(a), SolverSpec::Pcisph(b)) => b.xsph_c = a.xsph_c,
            (SolverSpec::Pcisph(a), SolverSpec::Pbf(b)) => b.xsph_c = a.xsph_c,
            (SolverSpec::Iisph(a), SolverSpec::Granular(b)) => b.iisph = a.iisph.clone(),
            (SolverSpec::Granular(a), SolverSpec::Iisph(b)) => b.iisph = a.iisph.clone(),
            _ => {}
        }
        to
    }
}
