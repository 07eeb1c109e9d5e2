//! The `[msm]` section: its keys checked against the geometry and the lattice options' own rules.

use super::*;

pub(super) fn check_msm(
    m: &MsmSpec,
    material: &MaterialModel,
    loads: &LoadsSpec,
    method: Method,
    info: Option<&GeomInfo>,
    p: &mut Problems,
) {
    let curve = info.is_some_and(|g| !g.surface);
    if let Some(kinds) = &m.elements {
        if kinds.is_empty() {
            p.push(
                "msm.elements",
                "[]",
                "list at least one kind of linear element",
            );
        }
        for (i, k) in kinds.iter().enumerate() {
            if kinds[..i].contains(k) {
                p.push(
                    "msm.elements",
                    format!("\"{}\"", k.name()),
                    "each kind may be listed once",
                );
            }
        }
        if curve {
            for k in kinds.iter().filter(|k| !LinearKind::CHAIN.contains(k)) {
                p.push(
                    "msm.elements",
                    format!("\"{}\"", k.name()),
                    "a curve's lattice has only spring_u, bend_u and third_u elements",
                );
            }
        }
    }
    // The spring keys are checked whatever the derivation: they also describe the lattice
    // `simulate --model msm` runs.
    for e in build::lattice_options(m, material, loads.gravity, Method::Paper, curve).problems() {
        match e {
            MsmError::InvalidOption { name, value, rule } => {
                let key = match name.strip_prefix("gravity") {
                    Some(rest) => format!("loads.gravity{rest}"),
                    None => format!("msm.{name}"),
                };
                p.push(key, format_f64(value), rule);
            }
            MsmError::NoSprings => p.push(
                "msm.structural",
                "false",
                "structural, shear and bending are all false: the lattice has no springs",
            ),
            other => p.push("msm", "", other.to_string()),
        }
    }
    let Some(g) = info else { return };
    let grid = m.grid_for(method);
    let (lu, lv) = match build::lattice_shape(&build::parameter_grid(m, method), &g.geometry) {
        Ok(shape) => shape,
        Err(MsmError::InvalidOption { name, value, rule }) => {
            if name != "nodes_v" || g.surface {
                p.push(format!("msm.{name}"), format_f64(value), rule);
            }
            return;
        }
        Err(MsmError::TooLarge { nodes }) => {
            p.push(
                if grid == LatticeGrid::Uniform {
                    "msm.nodes_u"
                } else {
                    "msm.grid"
                },
                if grid == LatticeGrid::Uniform && g.surface {
                    format!("{} x {} nodes", m.nodes_u, m.nodes_v)
                } else {
                    format!("{nodes} nodes")
                },
                format!(
                    "the lattice would have more than {} nodes",
                    nurbspring_msm::MAX_NODES
                ),
            );
            return;
        }
        Err(other) => {
            p.push("msm.grid", "", other.to_string());
            return;
        }
    };
    if let MsmFixed::Nodes(nodes) = &m.fixed {
        for (k, idx) in nodes.iter().enumerate() {
            let key = format!("msm.fixed[{k}]");
            let value = format!("{idx:?}");
            if idx.len() != if g.surface { 2 } else { 1 } {
                let want = if g.surface { "[a, b]" } else { "[a]" };
                p.push(key, value, format!("a lattice node is given as {want}"));
            } else if idx[0] >= lu || (g.surface && idx[1] >= lv) {
                p.push(key, value, format!("outside the {lu} x {lv} lattice"));
            }
        }
    }
}
