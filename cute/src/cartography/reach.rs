//! Reaching a target: the detour search and the unreachable flood, both over what the robot
//! can do. A state is (cell, heading); a FORWARD enters the cell ahead (not known blocked,
//! along a move not blocked) at that cell's cost; a LEFT or a RIGHT turns on the spot at
//! [`TURN_COST`], unless Carto has refused that turn from that cell and heading
//! ([`Cartographer::remember_failed_turn`]).
//!
//! So a cell where the robot cannot turn is driven through, and the robot turns round where it
//! can; of two detours of the same length the one with fewer turns is taken. The search is A*
//! with the Manhattan distance to the target, which never overestimates (every FORWARD costs at
//! least 1). The flood concludes a cell unreachable when no state of it can be reached.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use robot_model::grid::{Heading, Move};
use tracing::debug;

use super::{Cartographer, Known};
use crate::map::Map;

/// What a quarter turn costs, against 1 for a FORWARD into a known free cell.
pub const TURN_COST: u32 = 1;

/// No parent: the start state.
const NONE: u32 = u32::MAX;

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

    fn state(&self, cell: (u8, u8), h: Heading) -> Option<usize> {
        // `Heading::ALL` is in wire order: a heading's wire value is its index there
        Some(self.index(cell)? * 4 + usize::from(h.as_u8()))
    }

    fn cell_of(&self, state: usize) -> ((u8, u8), Heading) {
        let i = state / 4;
        (((i / self.cols) as u8, (i % self.cols) as u8), Heading::ALL[state % 4])
    }

    /// The states one command leads to from `(cell, h)`, with the command's cost: FORWARD into
    /// a cell not known blocked along a move not blocked (its cost is the cell's), and the two
    /// turns not seen failing there.
    fn successors(
        &self,
        map: &Map,
        cell: (u8, u8),
        h: Heading,
    ) -> impl Iterator<Item = ((u8, u8), Heading, u32)> {
        let ahead = h.step(cell, self.rows, self.cols).and_then(|n| {
            let cost = match self.classify(map, n) {
                Known::Blocked => return None,
                Known::Unknown => u32::from(self.unknown_cost),
                Known::Free => 1,
            };
            (!map.is_move_blocked(cell, n)).then_some((n, h, cost))
        });
        let turns = [Move::Left, Move::Right]
            .into_iter()
            .filter(move |&t| !self.turn_failed(cell, h, t))
            .map(move |t| (cell, h.after(t), TURN_COST));
        ahead.into_iter().chain(turns)
    }

    /// A* from the robot's cell and heading to any heading in `target`, over free (1) and
    /// unknown (`unknown_cost`) cells, round the blocked moves and the turns seen failing. On
    /// success the plan holds the cells the FORWARDs enter, the next one last.
    pub(super) fn plan_detour(&mut self, map: &Map, target: (u8, u8)) -> bool {
        self.stats.searches += 1;
        let Some(start) = self.state(self.pose, self.heading) else { return false };
        let n = self.rows * self.cols * 4;
        let mut cost = vec![u32::MAX; n];
        let mut parent = vec![NONE; n];
        let mut open = BinaryHeap::new();
        let h = |c: (u8, u8)| u32::from(c.0.abs_diff(target.0)) + u32::from(c.1.abs_diff(target.1));
        cost[start] = 0;
        open.push(Reverse((h(self.pose), start)));
        let mut goal = None;
        while let Some(Reverse((f, s))) = open.pop() {
            let (cell, heading) = self.cell_of(s);
            if f > cost[s] + h(cell) {
                continue; // a better way here was found after this entry was queued
            }
            if cell == target {
                goal = Some(s);
                break;
            }
            for (next, nh, step) in self.successors(map, cell, heading) {
                let Some(t) = self.state(next, nh) else { continue };
                let c = cost[s] + step;
                if c < cost[t] {
                    cost[t] = c;
                    parent[t] = s as u32;
                    open.push(Reverse((c + h(next), t)));
                }
            }
        }
        let Some(goal) = goal else { return false };
        debug!(?target, cost = cost[goal], "detour planned");
        let mut s = goal;
        while parent[s] != NONE {
            let p = parent[s] as usize;
            let (cell, _) = self.cell_of(s);
            if cell != self.cell_of(p).0 {
                self.plan.push(cell);
            }
            s = p;
        }
        !self.plan.is_empty()
    }

    /// Marks every unknown cell the robot cannot reach, in any heading, by FORWARDs not refused
    /// and turns not seen failing.
    pub(super) fn mark_unreachable(&mut self, map: &Map, target: (u8, u8)) {
        let before = self.stats.unreachable;
        let mut seen = vec![false; self.rows * self.cols * 4];
        let mut stack = Vec::new();
        if let Some(s) = self.state(self.pose, self.heading) {
            seen[s] = true;
            stack.push(s);
        }
        while let Some(s) = stack.pop() {
            let (cell, heading) = self.cell_of(s);
            for (next, nh, _) in self.successors(map, cell, heading) {
                if let Some(t) = self.state(next, nh)
                    && !seen[t]
                {
                    seen[t] = true;
                    stack.push(t);
                }
            }
        }
        let mut newly = 0;
        for i in 0..self.rows * self.cols {
            let c = ((i / self.cols) as u8, (i % self.cols) as u8);
            let reached = seen[i * 4..i * 4 + 4].iter().any(|&b| b);
            if !reached && !self.unreachable[i] && self.classify(map, c) == Known::Unknown {
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
