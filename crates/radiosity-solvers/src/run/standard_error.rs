//! [`StandardError`]: the error bar of a solver whose answer is an estimate, from the spread of
//! independent replicates, which needs no reference.
//!
//! `R ≥ 2` replicates `B^(1) … B^(R)`, each an unbiased estimate of the same solution from
//! independent random numbers, give the mean `B̄` (what the solver displays) and, patch by
//! patch and channel by channel, the standard error of that mean,
//!
//! `s_ic = sqrt( Σ_r (B^(r)_ic − B̄_ic)² / (R (R − 1)) )`.
//!
//! Its summary ([`StandardError::relative_rms`]) has the form of e_rms,
//! `sqrt( Σ_ic A_i s_ic² / Σ_ic A_i B̄_ic² )`, so that the two read side by side: `s²` is an
//! unbiased estimate of the variance of `B̄`, so the summary squared estimates the expected
//! e_rms squared of the mean, as far as the replicates are unbiased (what they are not, a
//! truncated series, no spread can see). Per patch, `(B̄ − B*) / s` follows Student's `t` with
//! `R − 1` degrees of freedom where the estimates are close to normal (many rays): within 2
//! standard errors about 86% of the time for `R = 4`, 94% for `R = 16`, 95% as `R` grows
//! ([`t_coverage_of_two`]).
//!
//! A certified bound (a deterministic solver's, docs/design.md §5) is a promise that holds every
//! time; a standard error is a statement about the spread, which the true error exceeds now
//! and then, at the rate above.

use radiosity_core::{LinearSystem, Real};

/// The standard error of a mean of independent replicates (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct StandardError {
    /// `s_ic`, patch-major like the radiosity.
    pub values: Vec<Real>,
    /// The replicates it rests on (`R ≥ 2`).
    pub replicates: usize,
}

impl StandardError {
    /// The mean of `replicates` (each patch-major, all of one length, at least two) into
    /// `mean`, and its standard error.
    pub fn of_replicates(replicates: &[&[Real]], mean: &mut [Real]) -> StandardError {
        let r = replicates.len();
        assert!(r >= 2, "a standard error needs two replicates at least");
        let mut values = vec![0.0; mean.len()];
        for (idx, (m, s)) in mean.iter_mut().zip(&mut values).enumerate() {
            let avg = replicates.iter().map(|b| b[idx]).sum::<Real>() / r as Real;
            let ss: Real = replicates.iter().map(|b| (b[idx] - avg).powi(2)).sum();
            *m = avg;
            *s = (ss / (r * (r - 1)) as Real).sqrt();
        }
        StandardError { values, replicates: r }
    }

    /// `sqrt( Σ A s² / Σ A B̄² )` over every patch and channel of `system`, with `radiosity`
    /// the mean: the form of e_rms (module doc). Zero when `B̄` is zero everywhere.
    pub fn relative_rms(&self, system: &LinearSystem, radiosity: &[Real]) -> Real {
        let k = system.channels().count();
        let (mut num, mut den) = (0.0, 0.0);
        for (idx, (&s, &b)) in self.values.iter().zip(radiosity).enumerate() {
            let a = system.areas()[idx / k];
            num += a * s * s;
            den += a * b * b;
        }
        if den > 0.0 { (num / den).sqrt() } else { 0.0 }
    }
}

/// `P(|t| ≤ 2)` for Student's `t` with `replicates − 1` degrees of freedom: how often the
/// true error of a normal estimate lies within 2 of its standard errors (module doc).
/// Computed by Simpson's rule on the density; `replicates ≥ 2`.
pub fn t_coverage_of_two(replicates: usize) -> Real {
    let nu = (replicates.max(2) - 1) as Real;
    // The density up to its constant; the constant from the integral over a wide range.
    let density = |t: Real| (1.0 + t * t / nu).powf(-(nu + 1.0) / 2.0);
    let simpson = |a: Real, b: Real, m: usize| {
        let h = (b - a) / m as Real;
        let inner: Real = (1..m).map(|k| if k % 2 == 1 { 4.0 } else { 2.0 } * density(a + k as Real * h)).sum();
        h / 3.0 * (density(a) + density(b) + inner)
    };
    // The tail beyond 200 by its power law: ∫_200^∞ t^-(ν+1) (ν)^((ν+1)/2) dt.
    let tail = nu.powf((nu + 1.0) / 2.0) * 200f64.powf(-nu) / nu;
    let within = simpson(0.0, 2.0, 2000);
    within / (within + simpson(2.0, 200.0, 200_000) + tail)
}
