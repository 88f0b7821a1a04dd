//! The dead end of a seam: a trim loop on a periodic surface that runs round it and out along
//! a seam (an edge it uses both ways) to a vertex where no other edge meets it bounds the band
//! the seam spans, and is closed across the period there, by the tessellator
//! (`tessellate::trimmed::loops`) and by the fidelity measure (`check::fidelity`) alike.

/// Of a loop's points, given in order as (their coordinate along the seam, whether they lie on
/// a seam), the seam point farthest beyond every point not on a seam, with its index: the
/// seam's dead end. `None` when no seam point lies beyond them, as where another edge meets the
/// seam's far end (generated model gen-2-39's shelled loft, its offset face bounded by a seam
/// between the bottom curve and a degenerate edge at the top: a loop that starts at the top
/// had been closed at the bottom, and the face drawn as a sliver), or when no point is off a
/// seam.
pub(crate) fn seam_dead_end(points: impl IntoIterator<Item = (f64, bool)>) -> Option<(usize, f64)> {
    let pts: Vec<(f64, bool)> = points.into_iter().collect();
    let (lo, hi) = pts
        .iter()
        .filter(|p| !p.1)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
    if lo > hi {
        return None;
    }
    pts.iter()
        .enumerate()
        .filter(|(_, p)| p.1)
        .map(|(k, p)| (k, p.0, (p.0 - hi).max(lo - p.0)))
        .filter(|&(_, t, beyond)| beyond > 1e-9 * (1.0 + t.abs()))
        .max_by(|a, b| a.2.total_cmp(&b.2))
        .map(|(k, t, _)| (k, t))
}

#[cfg(test)]
mod tests {
    use super::seam_dead_end;

    #[test]
    fn the_dead_end_is_the_seam_point_beyond_the_other_edges() {
        // A circle at v 0, a seam out to v 1.24 and back.
        let band = [
            (0.0, false),
            (0.0, false),
            (0.0, true),
            (0.6, true),
            (1.24, true),
            (0.6, true),
        ];
        assert_eq!(seam_dead_end(band), Some((4, 1.24)));
        // The same seam with an edge at its far end too: no dead end.
        let both = [
            (0.0, false),
            (0.0, true),
            (1.0, true),
            (1.0, false),
            (1.0, true),
            (0.0, true),
        ];
        assert_eq!(seam_dead_end(both), None);
        // Beyond below as well as above.
        let below = [(0.0, false), (0.0, true), (-2.0, true), (0.0, true)];
        assert_eq!(seam_dead_end(below), Some((2, -2.0)));
        assert_eq!(seam_dead_end([(0.0, true), (1.0, true)]), None);
    }
}
