//! Summary statistics shared by the profiler, the benchmarks, the examples and the viewer's
//! panel, so that every printed "median" means the same thing.

/// Median of the finite values of `values`; 0 when there are none.
///
/// An even count gives the mean of the two middle values (`[1, 2, 4, 8]` → 3), the textbook
/// definition: it does not lean towards the faster or the slower of two runs. NaN and ±∞ are
/// left out (a timing that failed should not move the result), and the sort uses
/// [`f64::total_cmp`], a total order, so no input can make it panic.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn odd_counts_take_the_middle_value() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[5.0]), 5.0);
        assert_eq!(median(&[9.0, -1.0, 4.0, 4.0, 100.0]), 4.0);
    }

    #[test]
    fn even_counts_average_the_two_middle_values() {
        // Not 2 (lower middle) nor 4 (upper middle): (2 + 4) / 2.
        assert_eq!(median(&[8.0, 1.0, 4.0, 2.0]), 3.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[1.0, 2.0]), 1.5);
    }

    #[test]
    fn non_finite_values_are_left_out() {
        assert_eq!(median(&[]), 0.0);
        assert_eq!(median(&[f64::NAN]), 0.0);
        assert_eq!(median(&[f64::NAN, 1.0]), 1.0);
        // Without the filter the infinities would be the two middle values of six.
        let v = [f64::INFINITY, 2.0, f64::NEG_INFINITY, 1.0, f64::NAN, 3.0];
        assert_eq!(median(&v), 2.0);
    }

    #[test]
    fn the_input_order_does_not_matter() {
        let v = [0.3, 7.0, 1.5, 2.25, 0.0, 11.0];
        let mut r = v;
        r.reverse();
        assert_eq!(median(&v), median(&r));
        assert_eq!(median(&v), 0.5 * (1.5 + 2.25));
    }
}
