//! Pixel selection for a template with a point budget ([`MotionLevel::max_points`]).
//!
//! The candidates are the pixels the plain template takes (every `stride`-th valid
//! pixel away from the border). When there are more than the budget, each gets a
//! score from both of its gradients, each normalised by its mean over the
//! candidates so that neither unit dominates:
//!
//! `s = min(max(|∇I|² / mean |∇I|², |∇log Z|² / mean |∇log Z|²), SCORE_CAP)`
//!
//! (`|∇log Z| = |∇Z| / Z`, missing when a neighbour has no depth, then 0). A
//! textured poster on a flat wall scores by its intensity edges, a blank wall with
//! depth structure by its depth gradient, and a scene with both keeps the best of
//! each kind. Above [`SCORE_CAP`] every candidate is as good as any other: picking
//! the steepest pixel of every edge raised the spread of the residuals (the robust
//! scale, which MOTION's spread check compares with fixed limits) and lost a frame
//! of fr1/desk that every-pixel tracking did not lose.
//!
//! The points are spread over the image as in DSO: the candidate grid is cut into
//! square cells of `d x d` candidates, `d = round(√(candidates / budget))` (about
//! one cell per point), and the best of each cell is taken first; if the cell
//! winners exceed the budget, the best-scoring winners are kept, otherwise all
//! winners plus the best of the rest. "Best" is a threshold found by selection (no
//! sort); the places left at the threshold are spread evenly over the candidates
//! tied at it in row-major order, so the choice is deterministic and a cap reached
//! by many does not favour the top of the image. The template keeps row-major order. All buffers are reused.
//!
//! [`MotionLevel::max_points`]: crate::config::MotionLevel::max_points

use super::Sample;

/// The highest normalised score: a gradient (squared) of twice the mean or more.
const SCORE_CAP: f32 = 2.0;

/// Scratch buffers of the selection, reused from frame to frame.
#[derive(Clone, Debug, Default)]
pub(crate) struct Selector {
    /// Pixel index of each candidate, row-major.
    pixel: Vec<u32>,
    /// Grid column and row of each candidate (packed), then its cell.
    cell: Vec<u32>,
    /// `|∇I|²` then the combined score of each candidate.
    score: Vec<f32>,
    /// `|∇log Z|²` of each candidate.
    depth_score: Vec<f32>,
    /// Per cell: the winning candidate (`u32::MAX` for none).
    best: Vec<u32>,
    /// Per candidate: 1 when kept.
    keep: Vec<u8>,
    /// Scores to find a threshold among.
    pool: Vec<f32>,
}

impl Selector {
    /// The indices (into the level's pixels, row-major) of at most `budget` of the
    /// candidates on the grid `(start..w-1).step_by(stride)` x
    /// `(start..h-1).step_by(stride)` with finite depth, passed to `emit` in
    /// row-major order. All candidates when there are at most `budget`.
    pub(crate) fn select(
        &mut self,
        samples: &[Sample],
        w: usize,
        h: usize,
        stride: usize,
        start: usize,
        budget: usize,
        mut emit: impl FnMut(usize),
    ) {
        self.pixel.clear();
        self.score.clear();
        self.depth_score.clear();
        self.cell.clear();
        // One pass over the candidates: where they are (grid column and row, packed,
        // until the cell size is known) and their gradients.
        let (mut sum_i, mut sum_z) = (0.0f64, 0.0f64);
        let (mut gw, mut gh) = (0usize, 0usize);
        for (gy, y) in (start..h.saturating_sub(1)).step_by(stride).enumerate() {
            gh = gy + 1;
            let row = &samples[y * w..(y + 1) * w];
            for (gx, x) in (start..w - 1).step_by(stride).enumerate() {
                gw = gx + 1;
                let s = &row[x];
                let z = s[super::D];
                if !z.is_finite() {
                    continue;
                }
                let gi = s[1] * s[1] + s[2] * s[2];
                let gz = (s[4] * s[4] + s[5] * s[5]) / (z * z);
                let gz = if gz.is_finite() { gz } else { 0.0 };
                sum_i += gi as f64;
                sum_z += gz as f64;
                self.pixel.push((y * w + x) as u32);
                self.cell.push((gx | gy << 16) as u32);
                self.score.push(gi);
                self.depth_score.push(gz);
            }
        }
        let n = self.pixel.len();
        if n <= budget {
            for &p in &self.pixel {
                emit(p as usize);
            }
            return;
        }
        // Cell side in candidates: about `budget` cells over the valid candidates
        // (counted, so that holes in the depth do not leave the budget unused).
        let d = ((n as f64 / budget.max(1) as f64).sqrt().round() as usize).max(1);
        let cells_x = gw.div_ceil(d);
        let cells = cells_x * gh.div_ceil(d);
        for c in &mut self.cell {
            let (gx, gy) = (*c as usize & 0xffff, *c as usize >> 16);
            *c = ((gy / d) * cells_x + gx / d) as u32;
        }
        // Normalised scores; a gradient that is zero everywhere adds nothing.
        let inv = |sum: f64| {
            if sum > 0.0 {
                (n as f64 / sum) as f32
            } else {
                0.0
            }
        };
        let (ki, kz) = (inv(sum_i), inv(sum_z));
        for (s, &z) in self.score.iter_mut().zip(&self.depth_score) {
            *s = (*s * ki).max(z * kz).min(SCORE_CAP);
        }
        // The best candidate of each cell (the first in row-major order on a tie).
        self.best.clear();
        self.best.resize(cells, u32::MAX);
        for (k, (&c, &s)) in self.cell.iter().zip(&self.score).enumerate() {
            let b = &mut self.best[c as usize];
            if *b == u32::MAX || s > self.score[*b as usize] {
                *b = k as u32;
            }
        }
        self.keep.clear();
        self.keep.resize(n, 0);
        let mut winners = 0usize;
        for &b in &self.best {
            if b != u32::MAX {
                self.keep[b as usize] = 1;
                winners += 1;
            }
        }
        // Among the winners if they are enough, else among the others to fill up.
        let (among, wanted) = if winners >= budget {
            (1u8, budget)
        } else {
            (0u8, budget - winners)
        };
        self.pool.clear();
        self.pool.extend(
            self.score
                .iter()
                .zip(&self.keep)
                .filter(|&(_, &k)| k == among)
                .map(|(&s, _)| s),
        );
        let (_, &mut tau, _) = self
            .pool
            .select_nth_unstable_by(wanted - 1, |a, b| b.total_cmp(a));
        let above = self
            .pool
            .iter()
            .filter(|&&s| s.total_cmp(&tau).is_gt())
            .count();
        let ties = self
            .pool
            .iter()
            .filter(|&&s| s.total_cmp(&tau).is_eq())
            .count();
        // The `wanted - above` places left go to candidates at the threshold (many
        // when scores reach the cap), spread evenly over them in row-major order.
        let places = wanted - above;
        let mut tie = 0usize;
        for (k, &s) in self.score.iter().enumerate() {
            if self.keep[k] != among {
                continue;
            }
            let take = match s.total_cmp(&tau) {
                std::cmp::Ordering::Greater => true,
                std::cmp::Ordering::Equal => {
                    tie += 1;
                    tie * places / ties > (tie - 1) * places / ties
                }
                _ => false,
            };
            // 2: taken now; a winner not taken is dropped (1 becomes 0).
            self.keep[k] = if take { 2 } else { 0 };
        }
        for (k, &p) in self.pixel.iter().enumerate() {
            if self.keep[k] != 0 {
                emit(p as usize);
            }
        }
    }
}
