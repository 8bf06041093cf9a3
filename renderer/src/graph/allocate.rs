//! Sharing allocations between resources whose lifetimes do not overlap.
//!
//! A resource lives from the pass that writes it to the last pass that reads it, both
//! inclusive: a pass never reads and writes one allocation. A retained output, and a resource
//! carried into the next frame, occupies its allocation for the whole frame, so it never
//! shares with anything. Resources with equal descriptors share when their lifetimes are
//! disjoint. This is colouring an interval graph, which the left-edge algorithm does optimally: take the
//! resources by start and give each the lowest-numbered allocation of its descriptor that is
//! free by then. The number of allocations per descriptor then equals the most resources of
//! that descriptor alive at once, the lower bound that [`lower_bound_bytes`] computes
//! independently (the seed paper's backwards colouring, §6.2, makes no such promise).

use std::collections::HashMap;

use super::{Resolved, Usage, Virtual};

/// One real texture or buffer and the resources it holds, one after another.
#[derive(Debug, Clone, PartialEq)]
pub struct Physical {
    pub desc: Resolved,
    /// The union of what every resource it holds needs.
    pub usage: Usage,
    pub resources: Vec<usize>,
    /// Allocations of the same descriptor are numbered 0, 1, … in order of the start of their
    /// first resource's span (retained outputs, which span the frame, first); a renderer can
    /// share allocation `ordinal` of a descriptor and usage between graphs that never run at
    /// the same time.
    pub ordinal: usize,
    /// It holds a resource carried into the next frame: a renderer keeps it for this graph
    /// alone.
    pub carried: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Allocation {
    pub physical: Vec<Physical>,
    /// The allocation of each resource.
    pub assignment: Vec<usize>,
}

impl Allocation {
    pub fn bytes(&self) -> u64 {
        self.physical.iter().map(|p| p.desc.bytes()).sum()
    }
}

/// The positions a resource keeps its allocation busy: its lifetime, or the whole frame
/// (retained and carried resources).
fn span(resource: &Virtual) -> (usize, usize) {
    if resource.retained.is_some() || resource.carried {
        (0, resource.last)
    } else {
        (resource.first, resource.last)
    }
}

pub(super) fn allocate(resources: &[Virtual]) -> Allocation {
    let mut by_start: Vec<usize> = (0..resources.len()).collect();
    by_start.sort_by_key(|&r| (span(&resources[r]).0, r));
    let mut physical: Vec<Physical> = Vec::new();
    // The last position each allocation is busy until.
    let mut busy_until: Vec<usize> = Vec::new();
    let mut assignment = vec![0; resources.len()];
    for r in by_start {
        let resource = &resources[r];
        let (start, end) = span(resource);
        let free = (0..physical.len()).find(|&p| physical[p].desc == resource.desc && busy_until[p] < start);
        let p = free.unwrap_or_else(|| {
            let ordinal = physical.iter().filter(|p| p.desc == resource.desc).count();
            physical.push(Physical {
                desc: resource.desc,
                usage: resource.usage,
                resources: Vec::new(),
                ordinal,
                carried: false,
            });
            busy_until.push(0);
            physical.len() - 1
        });
        physical[p].usage = physical[p].usage.union(resource.usage);
        physical[p].carried |= resource.carried;
        physical[p].resources.push(r);
        busy_until[p] = end;
        assignment[r] = p;
    }
    Allocation { physical, assignment }
}

/// Bytes of one allocation per resource: what a graph without sharing would take.
pub fn one_per_resource_bytes(resources: &[Virtual]) -> u64 {
    resources.iter().map(|r| r.desc.bytes()).sum()
}

/// Per descriptor, the most resources alive at one position, in bytes: no allocation can do
/// with less.
pub fn lower_bound_bytes(resources: &[Virtual]) -> u64 {
    let mut alive: HashMap<Resolved, Vec<(usize, usize)>> = HashMap::new();
    for r in resources {
        alive.entry(r.desc).or_default().push(span(r));
    }
    alive
        .iter()
        .map(|(desc, spans)| {
            let end = spans.iter().map(|s| s.1).max().unwrap_or(0);
            let most = (0..=end).map(|t| spans.iter().filter(|s| s.0 <= t && t <= s.1).count()).max();
            desc.bytes() * most.unwrap_or(0) as u64
        })
        .sum()
}
