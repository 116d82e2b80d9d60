//! The kernel's tails on log-spaced groups of bins. Far from `u'` the fine
//! bins (`5e-5 v_th` in the default study) hold few independent events: the
//! bath part of every bin there is a difference of a slow bath particle's
//! loss at its incoming velocity and its gain where its kick takes it, kicks
//! much wider than a bin (docs/benchmarks.md, "The far kernel"), so a fine
//! bin at `|u - u'| ~ 0.03` is uncertain by ~20% while `G` itself changes on
//! the scale `sigma ~ 0.02`. Groups whose width grows with `|u - u'|` (a
//! fixed fraction of a decade) resolve the tail with errors a reader can
//! trust, the way the paper draws it on log axes.

use crate::stats::Estimate;

/// Groups per decade of `|u - u'|` of the kernel's log-binned table: each
/// group spans a factor `10^(1/20) = 1.122`, i.e. its width is 11-12% of its
/// distance from `u'`.
pub const GROUPS_PER_DECADE: f64 = 20.0;

/// The bins at `x > 0` grouped on a log scale, `per_decade` groups per decade
/// counted down from the largest `x` (bin `k` joins group `ceil(per_decade
/// log10(x_k / x_max))`, so the outermost group is as wide as the others
/// rather than a lone bin on a decade's boundary). Each group lists its
/// members' indices into `x`, in ascending `x`; groups ascend too.
pub fn log_groups(x: &[f64], per_decade: f64) -> Vec<Vec<usize>> {
    let largest = x.iter().copied().fold(0.0, f64::max);
    let mut groups: Vec<(i64, Vec<usize>)> = Vec::new();
    let mut order: Vec<usize> = (0..x.len()).filter(|&k| x[k] > 0.0).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    for k in order {
        let group = (per_decade * libm::log10(x[k] / largest)).ceil() as i64;
        match groups.last_mut() {
            Some((last, members)) if *last == group => members.push(k),
            _ => groups.push((group, vec![k])),
        }
    }
    groups.into_iter().map(|(_, members)| members).collect()
}

/// The log-spaced groups ([`log_groups`], [`GROUPS_PER_DECADE`]) of the
/// bin centres `centres` on each side of `u'`: below (`-1`) then above
/// (`+1`), each side's groups in ascending `du`, with the side; members
/// nearest `u'` first.
pub fn sided_log_groups(centres: &[f64]) -> Vec<(f64, Vec<usize>)> {
    let mut groups = Vec::new();
    for side in [-1.0, 1.0] {
        let distance: Vec<f64> = centres.iter().map(|c| side * c).collect();
        let mut sided = log_groups(&distance, GROUPS_PER_DECADE);
        if side < 0.0 {
            sided.reverse();
        }
        groups.extend(sided.into_iter().map(|members| (side, members)));
    }
    groups
}

/// Mean over a group's bins of a per-bin quantity, per randomization
/// (`replicates[randomization][bin]`), with its standard error from the
/// spread of those means. Neighbouring bins share scenes (one slow launch
/// feeds many), so their errors do not add like those of independent bins.
pub fn group_mean(replicates: &[Vec<f64>], members: &[usize]) -> Estimate {
    let count = members.len() as f64;
    let means: Vec<f64> = replicates
        .iter()
        .map(|values| members.iter().map(|&k| values[k]).sum::<f64>() / count)
        .collect();
    Estimate::from_replicates(&means)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bin centres of a kernel window's positive side: `k w`, `k = 1..=500`,
    /// `w = 2e-4`, up to the edge at 0.1.
    fn window() -> Vec<f64> {
        (1..=500).map(|k| f64::from(k) * 2e-4).collect()
    }

    /// Every positive bin is in exactly one group; groups are contiguous in
    /// `x`, and each spans at most a factor `10^(1/20)` of bin centres.
    #[test]
    fn groups_partition_the_bins_into_twentieths_of_a_decade() {
        let x = window();
        let mut mirrored = x.clone();
        mirrored.extend(x.iter().map(|v| -v));
        let groups = log_groups(&mirrored, GROUPS_PER_DECADE);
        let mut seen: Vec<usize> = groups.concat();
        seen.sort_unstable();
        assert_eq!(seen, (0..x.len()).collect::<Vec<_>>());
        for members in &groups {
            let (low, high) = (x[members[0]], x[members[members.len() - 1]]);
            assert!(high / low <= libm::pow(10.0, 1.0 / 20.0) + 1e-12);
            assert!(members.windows(2).all(|pair| pair[1] == pair[0] + 1));
        }
    }

    /// The outermost group spans the top 1/20 of a decade, `(0.1 10^(-1/20),
    /// 0.1]`, like every other group. Before, groups were cut at multiples of
    /// 1/20 decade from 1, so the bin at 0.1 (on a boundary) was a group of
    /// its own: one bin's noise drawn as the kernel's end.
    #[test]
    fn the_outermost_group_is_as_wide_as_the_rest() {
        let x = window();
        let groups = log_groups(&x, GROUPS_PER_DECADE);
        let lower = 0.1 * libm::pow(10.0, -1.0 / 20.0);
        let top: Vec<usize> = (0..x.len()).filter(|&k| x[k] > lower).collect();
        assert!(top.len() > 50, "{}", top.len());
        assert_eq!(groups.last(), Some(&top));
    }

    /// Bins that move together over the randomizations (one slow launch
    /// feeds them all): the error of a group's mean is the spread of the
    /// randomizations' group means, `s / sqrt(R)` of the common shifts,
    /// whatever the number of bins; independent bins' errors added in
    /// quadrature would give `sqrt(n)` times less.
    #[test]
    fn a_group_of_correlated_bins_has_the_error_of_its_randomizations() {
        let x = window();
        let shifts = [0.3, -0.1, -0.4, 0.2, 0.0, 0.5, -0.3, -0.2];
        let replicates: Vec<Vec<f64>> = shifts.iter().map(|c| vec![1.0 + c; x.len()]).collect();
        let count = shifts.len() as f64;
        let mean = shifts.iter().sum::<f64>() / count;
        let variance = shifts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (count - 1.0);
        let expected = (variance / count).sqrt();
        let groups = log_groups(&x, GROUPS_PER_DECADE);
        assert!(groups.len() > 10);
        for members in &groups {
            let estimate = group_mean(&replicates, members);
            assert!((estimate.mean - (1.0 + mean)).abs() < 1e-12);
            assert!((estimate.stderr / expected - 1.0).abs() < 1e-12);
        }
    }
}
