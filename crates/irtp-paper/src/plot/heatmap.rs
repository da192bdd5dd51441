//! A heat map: one scalar over a grid of two categorical axes (the two
//! crossed axes of a sweep plan), each cell coloured by its value on the
//! viridis scale, with a colour bar. Cells without a value (a failed point,
//! a `nan`) are drawn light grey.
//!
//! The model needs no plotting library; rendering (`render_png`,
//! `render_svg`) uses `plotters` and exists only with the cargo feature
//! `plot`, like [`super::Figure`]'s.

use serde::Serialize;

/// A value per cell of an `x` × `y` grid.
#[derive(Clone, Debug, Serialize)]
pub struct HeatMap {
    /// Title over the map.
    pub title: String,
    /// Name of the horizontal axis.
    pub x_label: String,
    /// Name of the vertical axis.
    pub y_label: String,
    /// Name of the coloured quantity (the colour bar's label).
    pub value_label: String,
    /// Tick labels of the columns (left to right).
    pub x_ticks: Vec<String>,
    /// Tick labels of the rows (bottom to top).
    pub y_ticks: Vec<String>,
    /// `values[row][column]`; `None` or non-finite: no value.
    pub values: Vec<Vec<Option<f64>>>,
}

/// Viridis at five stops (0, 1/4, 1/2, 3/4, 1), interpolated linearly.
const VIRIDIS: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (253.0, 231.0, 37.0),
];

/// The viridis colour of `t` in [0, 1] (clamped).
pub fn viridis(t: f64) -> (u8, u8, u8) {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

impl HeatMap {
    /// The smallest and largest finite value (`None` when there is none).
    pub fn value_range(&self) -> Option<(f64, f64)> {
        let finite = self.values.iter().flatten().flatten().copied();
        let (lo, hi) = finite
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        (lo <= hi).then_some((lo, hi))
    }

    /// Where `v` lies between the smallest and the largest value (0.5 when
    /// they are equal).
    pub fn level(&self, v: f64) -> f64 {
        match self.value_range() {
            Some((lo, hi)) if hi > lo => (v - lo) / (hi - lo),
            _ => 0.5,
        }
    }

    /// Render to a PNG file.
    #[cfg(feature = "plot")]
    pub fn render_png(&self, path: &std::path::Path) -> irtp::error::Result<()> {
        super::render::heatmap_png(self, path)
    }

    /// Render to an SVG file.
    #[cfg(feature = "plot")]
    pub fn render_svg(&self, path: &std::path::Path) -> irtp::error::Result<()> {
        super::render::heatmap_svg(self, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), (68, 1, 84));
        assert_eq!(viridis(1.0), (253, 231, 37));
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
        assert_eq!(viridis(0.5), (33, 145, 140));
    }

    #[test]
    fn range_skips_missing_and_non_finite_cells() {
        let h = HeatMap {
            title: String::new(),
            x_label: "a".into(),
            y_label: "b".into(),
            value_label: "v".into(),
            x_ticks: vec!["1".into(), "2".into()],
            y_ticks: vec!["3".into()],
            values: vec![vec![Some(2.0), None], vec![Some(f64::NAN), Some(4.0)]],
        };
        assert_eq!(h.value_range(), Some((2.0, 4.0)));
        assert_eq!(h.level(3.0), 0.5);
    }
}
