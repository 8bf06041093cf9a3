//! A compiled graph as text (passes, ports, allocations, lifetimes) and as Graphviz.

use std::fmt::Write;

use super::{Graph, Plan, PortRef, Usage};

/// Lifetimes print as 1-based pass positions; "end" is after the frame (retained outputs).
fn position(plan: &Plan, at: usize) -> String {
    if at >= plan.order.len() { "end".to_string() } else { (at + 1).to_string() }
}

fn mib(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}

fn usage(usage: Usage) -> String {
    match usage {
        Usage::Texture(u) => format!("{u:?}"),
        Usage::Buffer(u) => format!("{u:?}"),
    }
}

impl<T> Graph<T> {
    /// The plan as a table: passes in order with their ports, then every allocation with the
    /// resources it holds, then the bytes against one allocation per output and the bound.
    pub fn describe(&self, plan: &Plan) -> String {
        let label = |r: PortRef| format!("{}.{}", plan.names[r.pass], r.port);
        let mut out = String::new();
        let dims = plan.dims;
        let _ = writeln!(
            out,
            "{} passes at {}×{} (M = {}), {} resources in {} allocations",
            plan.order.len(),
            dims.width,
            dims.height,
            dims.m,
            plan.resources.len(),
            plan.allocation.physical.len()
        );
        for (at, &pass) in plan.order.iter().enumerate() {
            let _ = writeln!(out, "\n{:>2}. {}", at + 1, plan.names[pass]);
            for port in &self.decl(pass).ports {
                let here = PortRef { pass, port: port.name };
                let Some(index) = plan.resource_of(here) else { continue };
                let resource = &plan.resources[index];
                let physical = plan.allocation.assignment[index];
                let lifetime =
                    format!("{}–{}", position(plan, resource.first), position(plan, resource.last));
                let (verb, link) = if port.access.writes() {
                    let readers: Vec<String> = resource.readers.iter().map(|r| label(*r)).collect();
                    let retained =
                        resource.retained.map(|o| format!(" [retained: {o:?}]")).unwrap_or_default();
                    (
                        "writes",
                        format!(
                            "→ {}{retained}",
                            if readers.is_empty() { "-".into() } else { readers.join(", ") }
                        ),
                    )
                } else if resource.carried {
                    ("reads ", format!("← {} of the previous frame", label(resource.writer)))
                } else {
                    ("reads ", format!("← {}", label(resource.writer)))
                };
                let _ = writeln!(
                    out,
                    "      {verb} {:<18} {:<15} #{physical:<3} {:<26} live {lifetime:<8} {link}",
                    port.name,
                    format!("{:?}", port.access),
                    resource.desc.to_string()
                );
            }
        }
        allocations(&mut out, plan);
        let _ = writeln!(
            out,
            "\nbytes: {} allocated, {} with one allocation per output, {} lower bound",
            mib(plan.allocated_bytes()),
            mib(plan.one_per_output_bytes()),
            mib(plan.lower_bound_bytes())
        );
        out
    }

    /// The plan as a Graphviz digraph: passes as boxes in submission order, an edge per
    /// connection labelled with its ports and allocation, retained outputs as ellipses.
    pub fn dot(&self, plan: &Plan) -> String {
        let mut out =
            String::from("digraph frame {\n  rankdir=LR;\n  node [shape=box, fontname=\"monospace\"];\n");
        for (at, &pass) in plan.order.iter().enumerate() {
            let _ = writeln!(out, "  p{pass} [label=\"{}. {}\"];", at + 1, plan.names[pass]);
        }
        for (index, resource) in plan.resources.iter().enumerate() {
            let physical = plan.allocation.assignment[index];
            // A carried resource reaches its readers in the next frame: dashed.
            let style = if resource.carried { ", style=dashed" } else { "" };
            for reader in &resource.readers {
                let _ = writeln!(
                    out,
                    "  p{} -> p{} [label=\"{} → {}\\n#{physical} {}\"{style}];",
                    resource.writer.pass, reader.pass, resource.writer.port, reader.port, resource.desc
                );
            }
            if let Some(output) = resource.retained {
                let _ = writeln!(out, "  out{index} [shape=ellipse, label=\"{output:?}\"];");
                let _ = writeln!(
                    out,
                    "  p{} -> out{index} [label=\"{}\\n#{physical} {}\"];",
                    resource.writer.pass, resource.writer.port, resource.desc
                );
            }
        }
        out.push_str("}\n");
        out
    }
}

/// The plan's allocations, each with the resources it holds in turn and their lifetimes.
fn allocations(out: &mut String, plan: &Plan) {
    let label = |r: PortRef| format!("{}.{}", plan.names[r.pass], r.port);
    let _ = writeln!(out, "\nallocations");
    for (index, physical) in plan.allocation.physical.iter().enumerate() {
        let held: Vec<String> = physical
            .resources
            .iter()
            .map(|&r| {
                let resource = &plan.resources[r];
                format!(
                    "{} ({}–{})",
                    label(resource.writer),
                    position(plan, resource.first),
                    position(plan, resource.last)
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "  #{index:<3} {:<26} {:>11}  {}\n        holds {}",
            physical.desc.to_string(),
            mib(physical.desc.bytes()),
            usage(physical.usage),
            held.join(", ")
        );
    }
}
