//! Composition checked before openusd composes it. openusd follows `inherits` and
//! `specializes` targets recursively without remembering where it has been (an arc into a
//! cycle overflows the stack, a lattice of arcs takes exponential time), and its cost per
//! prim grows with the cube of the prim's namespace depth. So before the stage is traversed,
//! the layers it will read — its layer stack, and every layer reached through references
//! and payloads, read here from the same resolver — are scanned:
//!
//! - no prim is nested more than [`MAX_DEPTH`] levels deep;
//! - the inherits/specializes graph has no cycle, no chain longer than [`MAX_CHAIN`] and at
//!   most [`MAX_WALKS`] walks through it in all;
//! - every reference and payload names a prim that exists (its prim path, or the target
//!   layer's `defaultPrim`), unless an ancestor of the target carries arcs of its own that
//!   could provide it.

use openusd::ar::{self, ResolvedPath, Resolver};
use openusd::sdf::{self, AbstractData, Value};
use openusd::usd;
use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::resolver::CheckedResolver;
use crate::error::{Error, Result};

/// Deepest prim namespace accepted (`/A/B` is 2 levels).
pub(super) const MAX_DEPTH: usize = 256;

/// Longest chain of inherits/specializes arcs accepted.
const MAX_CHAIN: usize = 64;

/// Walks openusd's recursion over inherits/specializes targets may take in all.
const MAX_WALKS: u64 = 1_000_000;

/// Layers read at most (the layer stack and those reached by references and payloads).
const MAX_LAYERS: usize = 4096;

/// What the checks need from one layer.
struct LayerFacts {
    id: String,
    /// Prim spec paths.
    prims: HashSet<String>,
    /// Prims that author arcs (references, payloads, inherits, specializes, variants).
    with_arcs: HashSet<String>,
    default_prim: Option<String>,
    /// (prim, absolute inherits/specializes targets).
    inherits: Vec<(String, Vec<String>)>,
    /// References and payloads: (prim, asset path as authored, target layer id, prim path).
    references: Vec<Reference>,
    /// Sublayer identifiers.
    sublayers: Vec<String>,
}

struct Reference {
    prim: String,
    asset: String,
    layer: Option<String>,
    target: Option<String>,
}

/// Runs every check on the stage opened from `file`.
pub(super) fn check(file: &Path, stage: &usd::Stage) -> Result<()> {
    let layers = collect(stage);
    for layer in &layers {
        check_depth(file, layer)?;
    }
    check_inherits(file, &layers)?;
    check_references(file, &layers)
}

/// The stage's loaded layers, then (breadth first) those their arcs and sublayers reach.
fn collect(stage: &usd::Stage) -> Vec<LayerFacts> {
    let resolver = CheckedResolver::default();
    let mut layers: Vec<LayerFacts> = stage
        .layer_identifiers()
        .iter()
        .filter_map(|id| stage.layer(id).map(|l| facts(id, l.data(), &resolver)))
        .collect();
    let mut known: HashSet<String> = layers.iter().map(|l| l.id.clone()).collect();
    let mut next = 0;
    while next < layers.len() && layers.len() < MAX_LAYERS {
        let wanted: Vec<String> = layers[next]
            .references
            .iter()
            .filter_map(|r| r.layer.clone())
            .chain(layers[next].sublayers.iter().cloned())
            .collect();
        for id in wanted {
            if known.insert(id.clone()) {
                if let Some(data) = read_layer(&resolver, &id) {
                    layers.push(facts(&id, data.as_ref(), &resolver));
                }
            }
        }
        next += 1;
    }
    layers
}

/// Reads the layer `id` as openusd would; `None` when it cannot (openusd reports that).
fn read_layer(resolver: &CheckedResolver, id: &str) -> Option<Box<dyn AbstractData>> {
    let resolved = resolver.resolve(id)?;
    let name = resolved.to_string_lossy().into_owned();
    let inner = ar::split_package_relative_path_inner(&name).map(|(_, inner)| inner);
    let ext = Path::new(inner.as_deref().unwrap_or(&name))
        .extension()?
        .to_str()?
        .to_ascii_lowercase();
    let format = sdf::LayerRegistry::find_by_extension(&ext)?;
    format.read(resolver, &resolved).ok()
}

fn facts(id: &str, data: &dyn AbstractData, resolver: &CheckedResolver) -> LayerFacts {
    let anchor = ResolvedPath::new(id);
    let layer_of =
        |asset: &str| (!asset.is_empty()).then(|| resolver.create_identifier(asset, Some(&anchor)));
    let root = sdf::Path::abs_root();
    let mut f = LayerFacts {
        id: id.to_string(),
        prims: HashSet::new(),
        with_arcs: HashSet::new(),
        default_prim: token(data, &root, "defaultPrim").map(|p| format!("/{p}")),
        inherits: Vec::new(),
        references: Vec::new(),
        sublayers: match field(data, &root, "subLayers") {
            Some(Value::StringVec(v)) => v.iter().filter_map(|s| layer_of(s)).collect(),
            _ => Vec::new(),
        },
    };
    for path in data.spec_paths() {
        if data.spec_type(&path) != Some(sdf::SpecType::Prim) {
            continue;
        }
        let name = path.as_str().to_string();
        let targets = inherit_targets(data, &path);
        let mut references = references(data, &path);
        let has_arcs = !targets.is_empty()
            || !references.is_empty()
            || field(data, &path, "variantSetNames").is_some();
        if has_arcs {
            f.with_arcs.insert(name.clone());
        }
        if !targets.is_empty() {
            f.inherits.push((name.clone(), targets));
        }
        for (asset, target) in references.drain(..) {
            f.references.push(Reference {
                prim: name.clone(),
                layer: layer_of(&asset),
                asset,
                target,
            });
        }
        f.prims.insert(name);
    }
    f
}

/// The absolute inherits and specializes targets authored on `path`.
fn inherit_targets(data: &dyn AbstractData, path: &sdf::Path) -> Vec<String> {
    let mut targets = Vec::new();
    for key in ["inheritPaths", "specializes"] {
        if let Some(Value::PathListOp(op)) = field(data, path, key) {
            let absolute = op.flatten().into_iter().map(|t| path.make_absolute(&t));
            targets.extend(absolute.map(|t| t.as_str().to_string()));
        }
    }
    targets
}

/// The references and payloads authored on `path`: (asset path, absolute prim path).
fn references(data: &dyn AbstractData, path: &sdf::Path) -> Vec<(String, Option<String>)> {
    let arc = |asset: &str, target: &sdf::Path| {
        let target = (!target.is_empty()).then(|| path.make_absolute(target).as_str().to_string());
        (asset.to_string(), target)
    };
    let mut out = Vec::new();
    if let Some(Value::ReferenceListOp(op)) = field(data, path, "references") {
        out.extend(
            op.flatten()
                .iter()
                .map(|r| arc(&r.asset_path, &r.prim_path)),
        );
    }
    match field(data, path, "payload") {
        Some(Value::PayloadListOp(op)) => out.extend(
            op.flatten()
                .iter()
                .map(|p| arc(&p.asset_path, &p.prim_path)),
        ),
        Some(Value::Payload(p)) => out.push(arc(&p.asset_path, &p.prim_path)),
        _ => {}
    }
    out
}

/// A field's value, `None` when absent or unreadable.
fn field(data: &dyn AbstractData, path: &sdf::Path, key: &str) -> Option<Value> {
    data.try_field(path, key)
        .ok()
        .flatten()
        .map(|v| v.into_owned())
}

fn token(data: &dyn AbstractData, path: &sdf::Path, key: &str) -> Option<String> {
    match field(data, path, key)? {
        Value::Token(t) => Some(t.as_str().to_string()),
        Value::String(s) => Some(s),
        _ => None,
    }
    .filter(|s| !s.is_empty())
}

/// No prim deeper than [`MAX_DEPTH`].
fn check_depth(file: &Path, layer: &LayerFacts) -> Result<()> {
    let Some(deep) = layer
        .prims
        .iter()
        .find(|p| p.matches('/').count() > MAX_DEPTH)
    else {
        return Ok(());
    };
    let shown: String = deep.chars().take(80).collect();
    Err(Error::usd(
        file,
        format!(
            "<{shown}…> is nested {} levels deep; at most {MAX_DEPTH} are supported",
            deep.matches('/').count()
        ),
    ))
}

/// The inherits/specializes graph over all layers: acyclic, shallow and not too entangled.
fn check_inherits(file: &Path, layers: &[LayerFacts]) -> Result<()> {
    let mut graph: HashMap<&str, Vec<&str>> = HashMap::new();
    for layer in layers {
        for (prim, targets) in &layer.inherits {
            graph
                .entry(prim.as_str())
                .or_default()
                .extend(targets.iter().map(String::as_str));
        }
    }
    // Per node: (walks from it, longest chain from it), once finished.
    let mut done: HashMap<&str, (u64, usize)> = HashMap::new();
    let mut total = 0u64;
    let mut starts: Vec<&str> = graph.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        let (walks, chain) = walk(file, &graph, &mut done, start)?;
        total = total.saturating_add(walks);
        if chain > MAX_CHAIN {
            let reason = format!(
                "<{start}> starts a chain of {chain} inherits/specializes arcs; at most \
                 {MAX_CHAIN} are supported"
            );
            return Err(Error::usd(file, reason));
        }
        if total > MAX_WALKS {
            let reason = "the inherits/specializes arcs are too entangled to compose (more \
                          than a million paths through them)";
            return Err(Error::usd(file, reason));
        }
    }
    Ok(())
}

/// Depth-first search from `start` with an explicit stack: the number of walks openusd's
/// recursion takes from each node (Σ over targets of 1 + theirs) and the longest chain.
fn walk<'g>(
    file: &Path,
    graph: &HashMap<&'g str, Vec<&'g str>>,
    done: &mut HashMap<&'g str, (u64, usize)>,
    start: &'g str,
) -> Result<(u64, usize)> {
    let mut on_path: HashSet<&str> = HashSet::new();
    let mut stack: Vec<(&str, usize)> = vec![(start, 0)];
    on_path.insert(start);
    while let Some(&mut (node, ref mut next)) = stack.last_mut() {
        let targets = graph.get(node).map_or(&[][..], Vec::as_slice);
        if let Some(&t) = targets.get(*next) {
            *next += 1;
            if done.contains_key(t) {
                continue;
            }
            if !on_path.insert(t) {
                return Err(Error::usd(
                    file,
                    format!("inherits/specializes arcs form a cycle through <{t}>"),
                ));
            }
            stack.push((t, 0));
            continue;
        }
        let mut walks = 0u64;
        let mut chain = 0usize;
        for t in targets {
            let (w, c) = done[t];
            walks = walks.saturating_add(w).saturating_add(1);
            chain = chain.max(c + 1);
        }
        done.insert(node, (walks, chain));
        on_path.remove(node);
        stack.pop();
    }
    Ok(done[start])
}

/// Every reference and payload names a prim that exists (see the module docs).
fn check_references(file: &Path, layers: &[LayerFacts]) -> Result<()> {
    let by_id: HashMap<&str, &LayerFacts> = layers.iter().map(|l| (l.id.as_str(), l)).collect();
    for layer in layers {
        for r in &layer.references {
            let (candidates, target): (Vec<&LayerFacts>, Option<&String>) = match &r.layer {
                None => (layers.iter().collect(), r.target.as_ref()),
                Some(id) => match by_id.get(id.as_str()) {
                    None => continue, // unresolved: openusd reports it
                    Some(t) => (
                        layer_stack(&by_id, t),
                        r.target.as_ref().or(t.default_prim.as_ref()),
                    ),
                },
            };
            let Some(target) = target else {
                return Err(Error::prim(
                    file,
                    &r.prim,
                    format!(
                        "references @{}@ without a prim path, and it has no defaultPrim",
                        r.asset
                    ),
                ));
            };
            if !candidates.iter().any(|l| provides(l, target)) {
                let place = if r.asset.is_empty() {
                    String::new()
                } else {
                    format!(" in @{}@", r.asset)
                };
                return Err(Error::prim(
                    file,
                    &r.prim,
                    format!("references <{target}>{place}, which does not exist"),
                ));
            }
        }
    }
    Ok(())
}

/// `root` and its sublayers, recursively.
fn layer_stack<'a>(
    by_id: &HashMap<&str, &'a LayerFacts>,
    root: &'a LayerFacts,
) -> Vec<&'a LayerFacts> {
    let mut stack = vec![root];
    let mut next = 0;
    while next < stack.len() {
        for id in &stack[next].sublayers {
            if let Some(&l) = by_id.get(id.as_str()) {
                if !stack.iter().any(|s| s.id == l.id) {
                    stack.push(l);
                }
            }
        }
        next += 1;
    }
    stack
}

/// `layer` has `target`, or an ancestor of it with arcs that may bring it.
fn provides(layer: &LayerFacts, target: &str) -> bool {
    if layer.prims.contains(target) {
        return true;
    }
    let mut p = target;
    while let Some((parent, _)) = p.rsplit_once('/') {
        if parent.is_empty() {
            return false;
        }
        if layer.with_arcs.contains(parent) {
            return true;
        }
        p = parent;
    }
    false
}
