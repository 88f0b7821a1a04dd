//! Strip blocks of the resident geometry: a patch's strips as a block that concatenates with
//! its neighbours' in one merged draw (see `render::resident`).

use crate::strips::{Join, RESTART};

/// A patch's strips as a block that concatenates with its neighbours' (see the module doc).
pub(super) fn strip_block(local: &[u32], join: Join) -> Vec<u32> {
    match join {
        Join::Restart => {
            let mut b = Vec::with_capacity(local.len() + 1);
            b.extend_from_slice(local);
            if !b.is_empty() {
                b.push(RESTART);
            }
            b
        }
        Join::Degenerate => {
            let joined = crate::strips::join_degenerate(local, &mut []);
            let (Some(&first), Some(&last)) = (joined.first(), joined.last()) else {
                return Vec::new();
            };
            // first, first: the window from the previous block's last index is zero-area
            // and the strip starts at an even index; last (twice when odd): so is the
            // window into the next block, which starts at an even index again.
            let mut b = Vec::with_capacity(joined.len() + 4);
            b.extend([first, first]);
            b.extend_from_slice(&joined);
            b.push(last);
            if b.len() % 2 == 1 {
                b.push(last);
            }
            b
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_blocks_concatenate_with_every_strip_at_an_even_index() {
        // Two patches' strips, each two strips joined by a restart.
        let a = strip_block(&[0, 1, 2, 3, 4, RESTART, 5, 6, 7], Join::Degenerate);
        let b = strip_block(&[10, 11, 12, RESTART, 13, 14, 15, 16], Join::Degenerate);
        assert_eq!(a.len() % 2, 0);
        assert_eq!(b.len() % 2, 0);
        let merged: Vec<u32> = a.iter().chain(&b).copied().collect();
        // Triangles with their strip orientation (odd positions swap the first two).
        let tris = |s: &[u32]| -> Vec<[u32; 3]> {
            s.windows(3)
                .enumerate()
                .map(|(k, w)| {
                    if k % 2 == 0 {
                        [w[0], w[1], w[2]]
                    } else {
                        [w[1], w[0], w[2]]
                    }
                })
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .collect()
        };
        let alone = |local: &[u32]| {
            let mut out = Vec::new();
            for s in local.split(|&i| i == RESTART) {
                out.extend(tris(s));
            }
            out
        };
        let mut want = alone(&[0, 1, 2, 3, 4, RESTART, 5, 6, 7]);
        want.extend(alone(&[10, 11, 12, RESTART, 13, 14, 15, 16]));
        assert_eq!(tris(&merged), want);
    }

    #[test]
    fn restart_blocks_end_in_a_restart() {
        assert_eq!(
            strip_block(&[0, 1, 2], Join::Restart),
            vec![0, 1, 2, RESTART]
        );
        assert!(strip_block(&[], Join::Restart).is_empty());
        assert!(strip_block(&[], Join::Degenerate).is_empty());
    }
}
