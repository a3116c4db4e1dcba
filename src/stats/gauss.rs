//! Gauss–Legendre quadrature: n nodes xᵢ on [−1, 1], the roots of Pₙ, with weights
//! wᵢ = 2/((1 − xᵢ²) Pₙ′(xᵢ)²), found by Newton from Tricomi's initial guesses.

use nephele_runtime::fitting::Legendre;

use std::f64::consts::PI;

/// Nodes and weights of the n-point rule on [−1, 1] (n ≥ 1), nodes increasing.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(n, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// Pₙ(x) and Pₙ′(x) = n (x Pₙ − Pₙ₋₁)/(x² − 1), by the recurrence.
fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    if n == 0 {
        return (1.0, 0.0);
    }
    let (p0, p1) = Legendre::new(x)
        .take(n + 1)
        .fold((0.0, 0.0), |(_, last), p| (last, p));
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

/// ∫_a^b f by `pieces` equal sub-intervals, each with the n-point rule.
pub fn integrate(
    f: &dyn Fn(f64) -> f64,
    a: f64,
    b: f64,
    rule: &(Vec<f64>, Vec<f64>),
    pieces: usize,
) -> f64 {
    integrate_n(&|x| [f(x)], a, b, rule, pieces)[0]
}

/// [`integrate`] of N functions at once (sharing their evaluations).
pub fn integrate_n<const N: usize>(
    f: &dyn Fn(f64) -> [f64; N],
    a: f64,
    b: f64,
    rule: &(Vec<f64>, Vec<f64>),
    pieces: usize,
) -> [f64; N] {
    let h = (b - a) / pieces as f64;
    let mut total = [0.0; N];
    for j in 0..pieces {
        let mid = a + h * (j as f64 + 0.5);
        for (x, w) in rule.0.iter().zip(&rule.1) {
            for (t, v) in total.iter_mut().zip(f(mid + 0.5 * h * x)) {
                *t += w * v;
            }
        }
    }
    total.map(|t| 0.5 * h * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly_and_smooth_functions_closely() {
        let rule = gauss_legendre(8);
        // Exact up to degree 2n − 1 = 15.
        let got = integrate(&|x: f64| x.powi(14) + x.powi(15), -1.0, 1.0, &rule, 1);
        assert!((got - 2.0 / 15.0).abs() < 1e-14, "{got}");
        let got = integrate(&|x: f64| x.exp(), 0.0, 2.0, &rule, 3);
        assert!((got - (2f64.exp() - 1.0)).abs() < 1e-13, "{got}");
        let w: f64 = gauss_legendre(33).1.iter().sum();
        assert!((w - 2.0).abs() < 1e-13);
    }
}
