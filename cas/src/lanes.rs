//! Packing isomorphic instructions into SIMD lanes: superword-level parallelism on the straight
//! line program (Larsen & Amarasinghe, "Exploiting superword level parallelism with multimedia
//! instruction sets", PLDI 2000).
//!
//! Straight-line equations of motion hold many groups of instructions that do the same thing
//! to different data: the entries M_i,j … M_i,j+3 of one row of four mass-matrix columns are
//! each `M_(i+1),c + s_i·Lx_c + c_i·Ly_c`. A code generator seeds such groups (here: outputs
//! whose stores are adjacent in memory), and [`Program::pack_lanes`] grows them towards the
//! inputs as long as the lanes stay isomorphic (same operation, operands again packable,
//! equal, or gathered from scalars) and independent of each other, keeps a grown tree when
//! it saves operations, and reorders the program so that each pack's lanes are adjacent. The
//! generator then emits one vector operation per pack.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

use crate::program::{Instr, Operand, Program};

/// A program reordered by [`Program::pack_lanes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Packed {
    /// The reordered program (commutative operands may be swapped; values are bit-identical).
    pub program: Program,
    /// Lane count of every pack.
    pub width: usize,
    /// First instruction of each pack, ascending: instructions `start..start + width` are the
    /// lanes, independent of each other, all multiplications or all additions and
    /// subtractions (a mix is `a + s·b` with s = ±1 per lane).
    pub packs: Vec<usize>,
    /// The ranges passed as `keep`, where they are now (still contiguous, same order inside).
    pub keep: Vec<Range<usize>>,
}

impl Packed {
    /// Every range that must stay within one function: the packs and the kept ranges.
    pub fn together(&self) -> Vec<Range<usize>> {
        let mut r: Vec<Range<usize>> = self
            .packs
            .iter()
            .map(|&s| s..s + self.width)
            .chain(self.keep.iter().filter(|r| !r.is_empty()).cloned())
            .collect();
        r.sort_by_key(|r| r.start);
        r
    }
}

/// Binary operations that can be packed: their class (additions and subtractions pack
/// together, as `a + s·b` with a sign per lane) and whether operand order may be swapped.
fn packable(i: &Instr) -> Option<(u8, bool)> {
    match i {
        Instr::Add(..) => Some((0, true)),
        Instr::Sub(..) => Some((0, false)),
        Instr::Mul(..) => Some((1, true)),
        _ => None,
    }
}

fn operands(i: &Instr) -> [Operand; 2] {
    match *i {
        Instr::Add(a, b) | Instr::Sub(a, b) | Instr::Mul(a, b) => [a, b],
        _ => unreachable!("only binary operations are packed"),
    }
}

/// Steps an independence check may take before it gives up (and calls the lanes dependent).
const INDEPENDENCE_BUDGET: usize = 20_000;

struct Packer<'a> {
    prog: &'a Program,
    width: usize,
    /// Pack number of each instruction (committed or of the tree being grown).
    pack_of: Vec<u32>,
    /// Committed packs, lanes in order; then the tentative ones of the tree being grown.
    packs: Vec<Vec<u32>>,
    /// Swapped commutative operands, per instruction.
    swapped: Vec<bool>,
    /// Tentative swaps of the tree being grown.
    tentative_swaps: Vec<u32>,
    /// Vectors of scalars (gathers and splats) the tree being grown needs, each counted once.
    built: Vec<Vec<Operand>>,
    /// Visit stamps of the independence check.
    stamp: Vec<u32>,
    generation: u32,
}

const NONE: u32 = u32::MAX;

/// What a tree being grown has added so far (see [`Packer::undo`]).
#[derive(Clone, Copy)]
struct Mark {
    packs: usize,
    swaps: usize,
    built: usize,
}

impl<'a> Packer<'a> {
    fn new(prog: &'a Program, width: usize) -> Self {
        let n = prog.instrs.len();
        Packer {
            prog,
            width,
            pack_of: vec![NONE; n],
            packs: Vec::new(),
            swapped: vec![false; n],
            tentative_swaps: Vec::new(),
            built: Vec::new(),
            stamp: vec![0; n],
            generation: 0,
        }
    }

    fn mark(&self) -> Mark {
        Mark {
            packs: self.packs.len(),
            swaps: self.tentative_swaps.len(),
            built: self.built.len(),
        }
    }

    /// Drops the packs, swaps and vectors added since `mark`.
    fn undo(&mut self, mark: Mark) {
        for pack in self.packs.drain(mark.packs..) {
            for t in pack {
                self.pack_of[t as usize] = NONE;
            }
        }
        self.tentative_swaps.truncate(mark.swaps);
        self.built.truncate(mark.built);
    }

    /// How alike two operands are, for orienting commutative lanes.
    fn likeness(&self, a: Operand, b: Operand) -> u8 {
        match (a, b) {
            _ if a == b => 3,
            (Operand::Tmp(x), Operand::Tmp(y)) => {
                let (px, py) = (
                    packable(&self.prog.instrs[x as usize]),
                    packable(&self.prog.instrs[y as usize]),
                );
                if px.is_some() && px.map(|p| p.0) == py.map(|p| p.0) {
                    2
                } else {
                    1
                }
            }
            (Operand::Sym(_), Operand::Sym(_)) | (Operand::Const(_), Operand::Const(_)) => 1,
            _ => 0,
        }
    }

    /// Whether no lane depends on another (depth-first search from each lane down to the
    /// earliest one).
    fn independent(&mut self, lanes: &[u32]) -> bool {
        let lowest = *lanes.iter().min().expect("lanes");
        let prog = self.prog;
        let mut budget = INDEPENDENCE_BUDGET;
        for &start in lanes {
            self.generation += 1;
            let g = self.generation;
            let mut stack = vec![start];
            while let Some(k) = stack.pop() {
                let mut dependent = false;
                prog.instrs[k as usize].for_each_operand(|o| {
                    if let Operand::Tmp(t) = o
                        && t >= lowest
                        && self.stamp[t as usize] != g
                    {
                        self.stamp[t as usize] = g;
                        dependent |= lanes.contains(&t);
                        stack.push(t);
                    }
                });
                if dependent {
                    return false;
                }
                budget = match budget.checked_sub(1) {
                    Some(b) => b,
                    None => return false,
                };
            }
        }
        true
    }

    /// Grows a pack from `lanes` (operands of the lanes of a user pack, or a seed); returns
    /// the operations it saves (negative when gathering scalars costs more).
    fn grow(&mut self, lanes: &[Operand]) -> i64 {
        let w = self.width as i64;
        if lanes.iter().all(|&o| o == lanes[0]) {
            return if self.note_vector(lanes) {
                -i64::from(!matches!(lanes[0], Operand::Const(_)))
            } else {
                0
            };
        }
        let tmps: Option<Vec<u32>> = lanes
            .iter()
            .map(|&o| match o {
                Operand::Tmp(t) if self.pack_of[t as usize] == NONE => Some(t),
                _ => None,
            })
            .collect();
        let gather = |s: &mut Self| if s.note_vector(lanes) { -w } else { 0 };
        let Some(tmps) = tmps else {
            return gather(self);
        };
        let kind = packable(&self.prog.instrs[tmps[0] as usize]);
        let Some((op, _)) = kind else {
            return gather(self);
        };
        let same = tmps
            .iter()
            .all(|&t| packable(&self.prog.instrs[t as usize]).map(|p| p.0) == Some(op));
        let mut distinct = tmps.clone();
        distinct.sort_unstable();
        distinct.dedup();
        if !same || distinct.len() != tmps.len() || !self.independent(&tmps) {
            return gather(self);
        }
        let mark = self.mark();
        let id = self.packs.len() as u32;
        for &t in &tmps {
            self.pack_of[t as usize] = id;
        }
        self.packs.push(tmps.clone());
        // Lane operands, commutative lanes oriented like lane 0.
        let first = operands(&self.prog.instrs[tmps[0] as usize]);
        let mut cols: [Vec<Operand>; 2] = [vec![first[0]], vec![first[1]]];
        for &t in &tmps[1..] {
            let lane = &self.prog.instrs[t as usize];
            let [a, b] = operands(lane);
            let keep = self.likeness(first[0], a) + self.likeness(first[1], b);
            let commutative = packable(lane).is_some_and(|p| p.1);
            let swap =
                commutative && self.likeness(first[0], b) + self.likeness(first[1], a) > keep;
            if swap {
                self.tentative_swaps.push(t);
            }
            let (a, b) = if swap { (b, a) } else { (a, b) };
            cols[0].push(a);
            cols[1].push(b);
        }
        let [c0, c1] = cols;
        // Additions mixed with subtractions need the signs applied: one more operation.
        let mixed = tmps
            .iter()
            .any(|&t| matches!(self.prog.instrs[t as usize], Instr::Add(..)))
            && tmps
                .iter()
                .any(|&t| matches!(self.prog.instrs[t as usize], Instr::Sub(..)));
        let packed = w - 1 - i64::from(mixed) + self.grow(&c0) + self.grow(&c1);
        // Gathering the lanes here instead may be cheaper than the subtree (which then
        // gathers several vectors further down): undo it.
        let gathering = if self.built[..mark.built]
            .iter()
            .any(|b| b.as_slice() == lanes)
        {
            0
        } else {
            -w
        };
        if packed < gathering {
            self.undo(mark);
            return gather(self);
        }
        packed
    }

    /// Records a vector built from scalars; `false` if the tree has built it already.
    fn note_vector(&mut self, lanes: &[Operand]) -> bool {
        if self.built.iter().any(|b| b.as_slice() == lanes) {
            false
        } else {
            self.built.push(lanes.to_vec());
            true
        }
    }
}

impl Program {
    /// Packs isomorphic instructions into groups of `width` lanes, grown from `seeds` (each a
    /// list of `width` temporaries, such as outputs stored next to each other), and reorders
    /// the program so that every pack's lanes are adjacent, lane 0 first. `keep` are ranges
    /// that must stay contiguous (such as [`Program::batch_sin_cos`]'s batch).
    ///
    /// A tree grown from a seed is kept when the operations its packs save exceed the vectors
    /// it must gather from scalars. Values are bit-identical: only commutative operands are
    /// swapped. If the packs cannot be ordered (lanes of two packs depending on each other
    /// crosswise), the program is returned unpacked.
    pub fn pack_lanes(&self, seeds: &[Vec<u32>], width: usize, keep: &[Range<usize>]) -> Packed {
        let n = self.instrs.len();
        let unpacked = || Packed {
            program: self.clone(),
            width,
            packs: Vec::new(),
            keep: keep.to_vec(),
        };
        if width < 2 || seeds.is_empty() {
            return unpacked();
        }
        let mut p = Packer::new(self, width);
        for seed in seeds {
            if seed.len() != width || seed.iter().any(|&t| t as usize >= n) {
                continue;
            }
            p.tentative_swaps.clear();
            p.built.clear();
            let start = p.mark();
            let lanes: Vec<Operand> = seed.iter().map(|&t| Operand::Tmp(t)).collect();
            let saved = p.grow(&lanes);
            if saved > 0 && p.packs.len() > start.packs {
                for &t in &p.tentative_swaps {
                    p.swapped[t as usize] = true;
                }
            } else {
                p.undo(start);
            }
        }
        if p.packs.is_empty() {
            return unpacked();
        }
        // Groups that must stay contiguous: packs, then the kept ranges; other instructions
        // are groups of one. Order the groups topologically, earliest first.
        let mut group_of = vec![NONE; n];
        let mut groups: Vec<Vec<u32>> = p.packs.clone();
        for (g, pack) in groups.iter().enumerate() {
            for &t in pack {
                group_of[t as usize] = g as u32;
            }
        }
        for r in keep.iter().filter(|r| !r.is_empty()) {
            if r.clone().any(|k| group_of[k] != NONE) {
                // A kept range overlapping a pack: give up packing rather than split it.
                return unpacked();
            }
            let g = groups.len() as u32;
            r.clone().for_each(|k| group_of[k] = g);
            groups.push(r.clone().map(|k| k as u32).collect());
        }
        for (k, g) in group_of.iter_mut().enumerate() {
            if *g == NONE {
                *g = groups.len() as u32;
                groups.push(vec![k as u32]);
            }
        }
        let mut users: Vec<Vec<u32>> = vec![Vec::new(); groups.len()];
        let mut waiting = vec![0usize; groups.len()];
        for (g, members) in groups.iter().enumerate() {
            let mut deps: Vec<u32> = Vec::new();
            for &k in members {
                self.instrs[k as usize].for_each_operand(|o| {
                    if let Operand::Tmp(t) = o {
                        let d = group_of[t as usize];
                        if d != g as u32 {
                            deps.push(d);
                        }
                    }
                });
            }
            deps.sort_unstable();
            deps.dedup();
            waiting[g] = deps.len();
            for d in deps {
                users[d as usize].push(g as u32);
            }
        }
        let key = |g: usize| groups[g].iter().min().copied().unwrap_or(0);
        let mut ready: BinaryHeap<Reverse<(u32, u32)>> = (0..groups.len())
            .filter(|&g| waiting[g] == 0)
            .map(|g| Reverse((key(g), g as u32)))
            .collect();
        let mut order: Vec<u32> = Vec::with_capacity(n);
        let mut start_of_group = vec![0usize; groups.len()];
        while let Some(Reverse((_, g))) = ready.pop() {
            start_of_group[g as usize] = order.len();
            order.extend(&groups[g as usize]);
            for &u in &users[g as usize] {
                waiting[u as usize] -= 1;
                if waiting[u as usize] == 0 {
                    ready.push(Reverse((key(u as usize), u)));
                }
            }
        }
        if order.len() != n {
            return unpacked();
        }
        let program = self.reordered(&order, |k| p.swapped[k]);
        let mut packs: Vec<usize> = (0..p.packs.len()).map(|g| start_of_group[g]).collect();
        packs.sort_unstable();
        let keep = keep
            .iter()
            .map(|r| {
                if r.is_empty() {
                    r.clone()
                } else {
                    let s = start_of_group[group_of[r.start] as usize];
                    s..s + r.len()
                }
            })
            .collect();
        Packed {
            program,
            width,
            packs,
            keep,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Symbol;

    #[test]
    fn lanes_reading_each_other_are_not_independent() {
        let q = |i| Operand::Sym(Symbol::q(i));
        // t0 = q0 + q1, t1 = t0·q2, t2 = q0 + q2, t3 = t2·q1, t4 = t1 + t3
        let prog = Program {
            instrs: vec![
                Instr::Add(q(0), q(1)),
                Instr::Mul(Operand::Tmp(0), q(2)),
                Instr::Add(q(0), q(2)),
                Instr::Mul(Operand::Tmp(2), q(1)),
                Instr::Add(Operand::Tmp(1), Operand::Tmp(3)),
            ],
            outputs: vec![Operand::Tmp(4)],
        };
        let mut p = Packer::new(&prog, 2);
        assert!(p.independent(&[0, 2]));
        assert!(p.independent(&[1, 3]));
        assert!(!p.independent(&[0, 1]), "t1 reads t0");
        assert!(!p.independent(&[2, 4]), "t4 reads t2 through t3");
        assert!(!p.independent(&[4, 0]), "in any order");
    }
}
