//! Reaching a target: the A* detour over free and unknown cells round the blocked moves, and
//! the flood that concludes which unknown cells the robot cannot reach (the module docs of
//! [`super`], "Detours" and "Unreachable cells").

use tracing::debug;

use super::{Cartographer, Known};
use crate::astar::TieBreak;
use crate::map::Map;
use crate::trajectory::fill_grid;
use robot_model::grid::Heading;

impl Cartographer {
    /// Marks `target` unreachable: the robot cannot get there from where it is.
    pub(super) fn give_up(&mut self, target: (u8, u8)) {
        if let Some(i) = self.index(target)
            && !self.unreachable[i]
        {
            self.unreachable[i] = true;
            self.stats.unreachable += 1;
        }
        self.target = None;
        self.plan.clear();
    }

    /// A* from the robot to `target` over free (1) and unknown (`unknown_cost`) cells, round the
    /// blocked moves.
    pub(super) fn plan_detour(&mut self, map: &Map, target: (u8, u8)) -> bool {
        fill_grid(&mut self.grid, map, self.unknown_cost);
        self.stats.searches += 1;
        let from = (usize::from(self.pose.0), usize::from(self.pose.1));
        let to = (usize::from(target.0), usize::from(target.1));
        match self.astar.search_with(&self.grid, from, to, TieBreak::Fast) {
            Some(path) => {
                debug!(?target, cost = path.cost, "detour planned");
                self.plan.extend(path.cells.iter().skip(1).rev().map(|&(x, y)| (x as u8, y as u8)));
                !self.plan.is_empty()
            }
            None => false,
        }
    }

    /// Marks every unknown cell the robot cannot reach through non-blocked cells and moves.
    pub(super) fn mark_unreachable(&mut self, map: &Map, target: (u8, u8)) {
        let before = self.stats.unreachable;
        self.flood_seen.fill(false);
        self.flood_stack.clear();
        if let Some(i) = self.index(self.pose) {
            self.flood_seen[i] = true;
            self.flood_stack.push(self.pose);
        }
        while let Some(c) = self.flood_stack.pop() {
            for h in Heading::ALL {
                let Some(n) = h.step(c, self.rows, self.cols) else {
                    continue;
                };
                let Some(i) = self.index(n) else { continue };
                if !self.flood_seen[i]
                    && self.classify(map, n) != Known::Blocked
                    && !map.is_move_blocked(c, n)
                {
                    self.flood_seen[i] = true;
                    self.flood_stack.push(n);
                }
            }
        }
        let mut newly = 0;
        for i in 0..self.rows * self.cols {
            let c = ((i / self.cols) as u8, (i % self.cols) as u8);
            if !self.flood_seen[i] && !self.unreachable[i] && self.classify(map, c) == Known::Unknown {
                self.unreachable[i] = true;
                newly += 1;
            }
        }
        self.stats.unreachable += newly;
        // The search failed, so the target must be among them; make sure progress is made.
        self.give_up(target);
        debug!(?target, newly = self.stats.unreachable - before, "cells concluded unreachable");
    }
}
