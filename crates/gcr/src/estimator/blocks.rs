//! Blocks of output points: the unit that runs its rounds to the target on its own, and the unit
//! that shards split.
//!
//! With a target error the rounds stop on an error estimated over the points they run together
//! (`rounds.rs`), so a point's value depends on every point it runs with. Blocks bound that set:
//! the groups of neighbours that share paths (`neighbours.rs`, formed from the whole point set
//! in a Morton order) are cut, in that order, into blocks of at least
//! [`PathSettings::block_points`] points, and each block runs
//! its own rounds, guides included. A point's value then depends only on the whole point set's
//! grouping and on its block, never on which other blocks are computed: a shard (every N-th
//! block, [`crate::Shard`]) computes exactly the values a single run does.
//!
//! By default there is one block (`block_points = usize::MAX`): every point runs to the target
//! together, as before blocks existed; a run of up to `block_points` points is one block too.

use super::neighbours;
use crate::config::{PathSettings, Shard, SolveConfig};
use crate::domain::Domain;
use glam::DVec3;
use std::ops::Range;

/// The blocks of `groups` (in their order): runs of whole groups, each closed once it holds at
/// least `block_points` points; every group in exactly one block.
pub(crate) fn blocks(groups: &[Vec<usize>], block_points: usize) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let (mut start, mut points) = (0, 0);
    for (i, g) in groups.iter().enumerate() {
        points += g.len();
        if points >= block_points {
            out.push(start..i + 1);
            (start, points) = (i + 1, 0);
        }
    }
    if start < groups.len() {
        out.push(start..groups.len());
    }
    out
}

/// The blocks (indices, ascending) of `shard` among `blocks`: every `count`-th block from
/// `index` on, so that each shard holds blocks from all over the scene (contiguous runs of the
/// Morton order gave shards of unequal work: 2 shards of 20 000 Cornell-box probes, one ended at
/// 0.83 of the other's time). Every block when there is no shard.
pub(crate) fn of_shard(blocks: usize, shard: Option<Shard>) -> Vec<usize> {
    match shard {
        None => (0..blocks).collect(),
        Some(Shard { index, count }) => (index..blocks).step_by(count).collect(),
    }
}

/// The groups of neighbouring output points that share paths ([`neighbours::groups`], formed
/// from the whole point set), cut into blocks ([`blocks`]), and the blocks the configured shard
/// computes ([`of_shard`]): formed once per point set, read by the rounds and by the gathers
/// that estimate points one by one.
pub(crate) struct Blocks {
    /// The groups of neighbours (indices into the points).
    pub groups: Vec<Vec<usize>>,
    /// The blocks: runs of whole groups.
    pub blocks: Vec<Range<usize>>,
    /// The blocks (indices, ascending) the shard computes; every block without a shard.
    pub mine: Vec<usize>,
}

impl Blocks {
    /// The blocks of surface points `(point, normal, face)` (receivers in the air have
    /// [`scene_sampler::NO_FACE`]) under `settings`' group size, block size and shard.
    pub(crate) fn new(
        domain: &Domain,
        points: &[(DVec3, DVec3, u32)],
        settings: &PathSettings,
    ) -> Self {
        let groups = neighbours::groups(domain, points, settings.neighbours);
        let blocks = blocks(&groups, settings.block_points);
        let mine = of_shard(blocks.len(), settings.shard);
        Self {
            groups,
            blocks,
            mine,
        }
    }

    /// The points (indices, ascending) of the shard's blocks.
    pub(crate) fn points(&self) -> Vec<usize> {
        let mut out: Vec<usize> = (self.mine.iter())
            .flat_map(|&b| {
                self.groups[self.blocks[b].clone()]
                    .iter()
                    .flatten()
                    .copied()
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// The points (indices, ascending) of the shard's blocks ([`Self::points`]) among `count`,
    /// checked: an error when `settings` ask for a shard that has no block.
    pub(crate) fn estimated(
        &self,
        count: usize,
        settings: &PathSettings,
    ) -> Result<Vec<usize>, ShardError> {
        check_shard(self.mine.is_empty(), (self.blocks.len(), count), settings)?;
        Ok(self.points())
    }

    /// Whether each of `count` points is in the shard's blocks.
    pub(crate) fn mask(&self, count: usize) -> Vec<bool> {
        let mut mine = vec![false; count];
        self.points().into_iter().for_each(|i| mine[i] = true);
        mine
    }
}

/// The points (indices into `points`, ascending) of the shard `config` asks for
/// ([`PathSettings::shard`]; every point without one), as the paths gather forms its blocks
/// (`Blocks`): radiosity at surface points `(point, normal, face)`, or irradiance
/// (`irradiance`: the faces are ignored, every point is a white receiver). Errors when the shard
/// has no block: fewer blocks than shards.
pub fn shard_points(
    domain: &Domain,
    points: &[(DVec3, DVec3, u32)],
    irradiance: bool,
    config: &SolveConfig,
) -> Result<Vec<usize>, ShardError> {
    let receivers: Vec<_>;
    let points = match irradiance {
        true => {
            receivers = (points.iter())
                .map(|&(y, n, _)| (y, n, scene_sampler::NO_FACE))
                .collect();
            &receivers
        }
        false => points,
    };
    Blocks::new(domain, points, &config.paths).estimated(points.len(), &config.paths)
}

/// An error when `settings` ask for a shard and it has no block (`empty`) of the `blocks` blocks
/// of `points` points (probes, texels, or an image's strips of pixels).
pub(crate) fn check_shard(
    empty: bool,
    (blocks, points): (usize, usize),
    settings: &PathSettings,
) -> Result<(), ShardError> {
    match (settings.shard, empty) {
        (Some(shard), true) => Err(ShardError::Empty {
            shard,
            blocks,
            points,
            block_points: settings.block_points,
        }),
        _ => Ok(()),
    }
}

/// A shard that cannot be formed.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// More shards than blocks.
    #[error(
        "shard {shard}: the {points} points make only {blocks} block(s){}, fewer than the \
         shards; use fewer shards or a smaller --block-points (every shard, and any single run \
         compared with them, must use the same)",
        match *block_points { usize::MAX => " (no --block-points: one block)".to_string(),
                              b => format!(" of at least {b} points") }
    )]
    Empty {
        /// The shard asked for.
        shard: Shard,
        /// The blocks there are.
        blocks: usize,
        /// The points.
        points: usize,
        /// The block size.
        block_points: usize,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_hold_whole_groups_of_at_least_the_block_size() {
        let groups: Vec<Vec<usize>> = [3, 1, 4, 1, 5, 9, 2, 6]
            .iter()
            .scan(0, |next, &len| {
                let g = (*next..*next + len).collect();
                *next += len;
                Some(g)
            })
            .collect();
        assert_eq!(blocks(&groups, 5), [0..3, 3..5, 5..6, 6..8]);
        assert_eq!(blocks(&groups, 1000), vec![0..8]);
        assert_eq!(
            blocks(&groups, 1),
            (0..8).map(|i| i..i + 1).collect::<Vec<_>>()
        );
        assert!(blocks(&[], 5).is_empty());
    }

    #[test]
    fn shards_split_the_blocks_evenly_and_cover_each_once() {
        for blocks in [1, 2, 7, 10, 64] {
            for count in 1..=blocks {
                let mut seen = vec![0; blocks];
                for index in 0..count {
                    let mine = of_shard(blocks, Some(Shard { index, count }));
                    assert!(!mine.is_empty() && mine.len() <= blocks.div_ceil(count));
                    mine.iter().for_each(|&b| seen[b] += 1);
                }
                assert!(seen.iter().all(|&s| s == 1));
            }
        }
        assert_eq!(of_shard(5, None), [0, 1, 2, 3, 4]);
        assert_eq!(of_shard(7, Some(Shard { index: 1, count: 3 })), [1, 4]);
        // more shards than blocks: the last is empty (`shard_points` refuses it)
        assert!(of_shard(2, Some(Shard { index: 2, count: 3 })).is_empty());
    }
}
