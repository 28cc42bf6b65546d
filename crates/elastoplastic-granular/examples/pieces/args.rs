//! The examples' `key=value` arguments, and the material they set.

use elastoplastic_granular::{ConeMatch, ElastoplasticParams};

type Error = Box<dyn std::error::Error>;

/// The `key=value` arguments of the command line.
pub struct Args(Vec<String>);

impl Args {
    /// The process's arguments.
    pub fn from_env() -> Self {
        Self(std::env::args().skip(1).collect())
    }

    /// The value given for `key`, if any.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .find_map(|a| a.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
    }

    /// The number given for `key`, or `default`; an error if it does not parse.
    pub fn num(&self, key: &str, default: f64) -> Result<f64, Error> {
        Ok(self
            .get(key)
            .map(str::parse)
            .transpose()?
            .unwrap_or(default))
    }

    /// The cone's match `match` (`ss` simple shear, `ps` plane strain, `psa` plane strain
    /// associated), or `default`.
    pub fn cone_match(&self, default: ConeMatch) -> Result<ConeMatch, Error> {
        match self.get("match") {
            None => Ok(default),
            Some("ss") => Ok(ConeMatch::SimpleShear),
            Some("ps") => Ok(ConeMatch::PlaneStrain),
            Some("psa") => Ok(ConeMatch::PlaneStrainAssociated),
            Some(other) => Err(format!("match={other}: expected ss, ps or psa").into()),
        }
    }

    /// The material and its spacing: `s` (0.02 m), `phi` (30°), `E` (5.84e5 Pa), `alpha`
    /// (α_Π, the solver's default), `u` the viscosity's fixed velocity scale (m/s; 0: the
    /// speed of sound), `match` (`default_match`). Returns the parameters, `s` and `phi`.
    pub fn material(
        &self,
        default_match: ConeMatch,
    ) -> Result<(ElastoplasticParams<f64>, f64, f64), Error> {
        let s = self.num("s", 0.02)?;
        let phi = self.num("phi", 30.0)?;
        let mut params = ElastoplasticParams::<f64>::for_spacing(s, phi);
        params.youngs_modulus = self.num("E", 5.84e5)?;
        params.viscosity_alpha = self.num("alpha", params.viscosity_alpha)?;
        let u = self.num("u", 0.0)?;
        params.viscosity_speed_m_s = (u > 0.0).then_some(u);
        params.cone_match = self.cone_match(default_match)?;
        Ok((params, s, phi))
    }
}
