//! Velocity bins around a reference velocity `u'`, shared by the collision
//! kernel (`kernel`: the +-1 histograms of `G(u' -> u)`) and the ring's
//! molecular dynamics (`physics::md`: the estimators of `h(u, t)`), so that
//! neither imports the other. Owns the bin geometry only: no counting, no
//! weights, no units beyond `v_th`.

/// Velocity bins centred on `u' + k * width`, `|k| <= half_bins`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bins {
    /// Bin width, `v_th`.
    pub width: f64,
    /// Bins on each side of the centre bin.
    pub half_bins: usize,
}

impl Bins {
    /// Bins covering a window of total width `window` around `u'`.
    pub fn for_window(window: f64, width: f64) -> Bins {
        Bins {
            width,
            half_bins: (0.5 * window / width).round() as usize,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        2 * self.half_bins + 1
    }

    /// `true` when there are no bins (never: the centre bin always exists).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Index of the bin holding relative velocity `x`, if inside the window.
    pub fn index(&self, x: f64) -> Option<usize> {
        let k = (x / self.width).round();
        (k.abs() <= self.half_bins as f64).then_some((k + self.half_bins as f64) as usize)
    }

    /// Centre of bin `index` relative to `u'`.
    pub fn centre(&self, index: usize) -> f64 {
        (index as f64 - self.half_bins as f64) * self.width
    }

    /// Half-width of the binned window, `width (half_bins + 1/2)`: the outer
    /// edges of the outermost bins relative to `u'`, `v_th`.
    pub fn half_width(&self) -> f64 {
        self.width * (self.half_bins as f64 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every velocity inside the window lands in the bin whose centre is
    /// nearest, and the outer edges are the half width.
    #[test]
    fn bins_hold_the_velocities_nearest_their_centres() {
        let bins = Bins::for_window(1.0, 0.1);
        assert_eq!((bins.len(), bins.half_bins), (11, 5));
        assert!((bins.half_width() - 0.55).abs() < 1e-15);
        assert_eq!(bins.index(0.0), Some(5));
        assert_eq!(bins.index(0.149), Some(6));
        assert_eq!(bins.index(-0.5), Some(0));
        assert_eq!(bins.index(0.56), None);
        for k in 0..bins.len() {
            assert_eq!(bins.index(bins.centre(k)), Some(k));
        }
    }
}
