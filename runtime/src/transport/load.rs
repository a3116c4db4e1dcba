//! Loading a `.ntt`: its arrays found, shaped and checked ([`super::format`] has the names,
//! shapes and limits), the tables built from them ([`super::tables`] evaluates them).

use super::domain::Domain;
use super::format::{
    collector_part, halo_part, increasing, names, need, parse_form, whole_numbers, Strides,
    MAX_GROUPS, MAX_NODES, U_STEPS,
};
use super::tables::{integrate_mean_cosine, TransportTables};
use crate::container::{Container, FormatError};

impl<'a> TransportTables<'a> {
    /// Loads the arrays (each of its shape, from the form's sizes and the grids' lengths) and
    /// checks their values (finite, increasing grids, packed depth ranges, the phase table).
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let mut t = Self::parse(&Container::from_bytes(bytes)?)?;
        t.check()?;
        t.domain = t.read_domain();
        t.mean_cosine = integrate_mean_cosine(&t);
        Ok(t)
    }

    /// Finds every array with its shape (from the form's sizes and the grids' lengths), all
    /// values finite.
    fn parse(c: &Container<'a>) -> Result<Self, FormatError> {
        let (form, q) = parse_form(c)?;
        let count = |name: &'static str| {
            c.find(name)
                .map(|a| a.len())
                .ok_or(FormatError::Missing(name))
        };
        let (g, l, m, n) = (
            count(names::GROUP_FIRST)?,
            count(names::MU_L_NODES)?,
            count(names::MU_V_NODES)?,
            count(names::THICKNESS)?,
        );
        if !(1..=MAX_GROUPS).contains(&g) || [l, m, n].iter().any(|k| !(1..=MAX_NODES).contains(k))
        {
            return Err(FormatError::BadArray(names::GROUP_FIRST));
        }
        let p = form.n_params(m, l);
        let theta_len = count(names::PHASE_THETA)?;
        let beta_len = g
            .checked_mul(p)
            .and_then(|x| x.checked_mul(q))
            .ok_or(FormatError::BadArray(names::BETA))?;
        Ok(TransportTables {
            collector: collector_part(c, g, m, l)?,
            form,
            q,
            strides: Strides::of(g, q),
            group_first: need(c, names::GROUP_FIRST, g)?,
            mu_l: need(c, names::MU_L_NODES, l)?,
            mu_v: need(c, names::MU_V_NODES, m)?,
            thickness: need(c, names::THICKNESS, n)?,
            ln_t_range: need(c, names::LN_T_RANGE, 2 * g)?,
            beta: need(c, names::BETA, beta_len)?,
            u_range: need(
                c,
                names::U_RANGE,
                [n, l, m]
                    .iter()
                    .try_fold(g, |acc, &k| acc.checked_mul(k))
                    .ok_or(FormatError::BadArray(names::U_RANGE))?,
            )?,
            t_ceiling: match c.find(names::T_CEILING) {
                Some(_) => Some(need(c, names::T_CEILING, g * n * l)?),
                None => None,
            },
            phase_theta: need(c, names::PHASE_THETA, theta_len)?,
            phase: need(c, names::PHASE, theta_len)?,
            halo: halo_part(c, g, n, l)?,
            mean_cosine: 0.0,
            domain: Domain {
                thickness: (0.0, 0.0),
                mu_l: (0.0, 0.0),
            },
        })
    }

    /// Checks the values the shapes do not: increasing grids, depth ranges packed as exact
    /// integers, a phase function of at least two non-negative values from 0° to 180°.
    fn check(&self) -> Result<(), FormatError> {
        for (a, name) in [
            (&self.mu_l, names::MU_L_NODES),
            (&self.mu_v, names::MU_V_NODES),
            (&self.thickness, names::THICKNESS),
            (&self.phase_theta, names::PHASE_THETA),
        ] {
            if !increasing(a) {
                return Err(FormatError::BadArray(name));
            }
        }
        if !whole_numbers(&self.u_range, (U_STEPS * U_STEPS - 1) as f32) {
            return Err(FormatError::BadArray(names::U_RANGE));
        }
        let n = self.phase_theta.len();
        let ends = (self.phase_theta.get(0), self.phase_theta.get(n.max(1) - 1));
        if n < 2 || ends != (Some(0.0), Some(180.0)) || self.phase.iter().any(|v| v < 0.0) {
            return Err(FormatError::BadArray(names::PHASE));
        }
        Ok(())
    }
}
