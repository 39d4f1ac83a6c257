//! Scalar truncated least squares by adaptive voting (TEASER++ translation, per component).
//!
//! x* = argmin_x Σ_i min((x − t_i)² / c_i², 1) for measurements t_i with bounds c_i. On every
//! stretch of the line between consecutive interval ends t_i ± c_i the set S of intervals
//! covering it is fixed, and the cost there is minimised by the weighted mean
//! x_S = Σ_S t_i/c_i² / Σ_S 1/c_i², with cost Σ_S (x_S − t_i)²/c_i² + (n − |S|). Sweeping the 2n
//! sorted ends and keeping the cheapest x_S is exact in O(n log n).

/// Outcome of [`scalar_tls`].
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarTls {
    /// The minimiser x*.
    pub estimate: f64,
    /// Per measurement: |x* − t_i| ≤ c_i.
    pub inliers: Vec<bool>,
}

/// Exact scalar TLS of `measurements` t_i with positive `bounds` c_i. `None` without measurements.
pub fn scalar_tls(measurements: &[f64], bounds: &[f64]) -> Option<ScalarTls> {
    debug_assert_eq!(measurements.len(), bounds.len(), "one bound per measurement");
    let n = measurements.len();
    if n == 0 {
        return None;
    }
    // Shift by one measurement so the running sums stay well conditioned.
    let origin = measurements[0];
    // (position, opens, index); opens sort before closes at the same position (closed intervals).
    let mut ends: Vec<(f64, bool, usize)> = Vec::with_capacity(2 * n);
    for (i, (&t, &c)) in measurements.iter().zip(bounds).enumerate() {
        ends.push((t - c, true, i));
        ends.push((t + c, false, i));
    }
    ends.sort_by(|x, y| x.0.total_cmp(&y.0).then(y.1.cmp(&x.1)).then(x.2.cmp(&y.2)));
    let (mut sum_w, mut sum_wt, mut sum_wt2, mut active) = (0.0, 0.0, 0.0, 0usize);
    let mut best = (n as f64, measurements[0]);
    for &(_, opens, i) in &ends {
        let w = 1.0 / (bounds[i] * bounds[i]);
        let t = measurements[i] - origin;
        let sign = if opens { 1.0 } else { -1.0 };
        sum_w += sign * w;
        sum_wt += sign * w * t;
        sum_wt2 += sign * w * t * t;
        if opens {
            active += 1;
        } else {
            active -= 1;
        }
        if opens && active > 0 {
            let mean = sum_wt / sum_w;
            let cost = (sum_wt2 - mean * sum_wt).max(0.0) + (n - active) as f64;
            if cost < best.0 {
                best = (cost, mean + origin);
            }
        }
    }
    let estimate = best.1;
    let inliers = measurements
        .iter()
        .zip(bounds)
        .map(|(&t, &c)| (estimate - t).abs() <= c * (1.0 + 1e-9))
        .collect();
    Some(ScalarTls { estimate, inliers })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn consistent_measurements_give_their_mean() {
        let fit = scalar_tls(&[1.0, 1.002, 0.998, 1.001], &[0.01; 4]).expect("measurements");
        assert!((fit.estimate - 1.00025).abs() < 1e-12, "{}", fit.estimate);
        assert!(fit.inliers.iter().all(|&i| i));
    }

    #[test]
    fn outliers_are_voted_out_even_when_they_agree_among_themselves() {
        // Five inliers at 2.0 ± 0.004 and three mutually consistent outliers at 5.0.
        let t = [2.0, 2.004, 1.996, 5.0, 2.002, 5.001, 1.998, 4.999];
        let fit = scalar_tls(&t, &[0.01; 8]).expect("measurements");
        assert!(
            (fit.estimate - 2.0).abs() < 1e-12,
            "mean of the five inliers, got {}",
            fit.estimate
        );
        assert_eq!(fit.inliers, [true, true, true, false, true, false, true, false]);
    }

    #[test]
    fn the_result_is_the_brute_force_minimiser() {
        let t = [0.3, 0.31, 0.5, 0.52, 0.51, 0.9, 0.305];
        let c = [0.02, 0.01, 0.03, 0.02, 0.05, 0.1, 0.02];
        let cost = |x: f64| -> f64 { t.iter().zip(&c).map(|(ti, ci)| ((x - ti) / ci).powi(2).min(1.0)).sum() };
        let fit = scalar_tls(&t, &c).expect("measurements");
        let brute = (0..=200_000)
            .map(|k| cost(k as f64 * 1e-5))
            .fold(f64::INFINITY, f64::min);
        assert!(cost(fit.estimate) <= brute + 1e-9, "{} > {brute}", cost(fit.estimate));
    }

    #[test]
    fn no_measurements_no_estimate() {
        assert_eq!(scalar_tls(&[], &[]), None);
    }
}
