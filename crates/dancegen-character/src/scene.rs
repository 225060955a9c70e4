//! The character's node hierarchy: rest transforms, parents, a parents-first order, and forward
//! kinematics over arbitrary node transforms.
//!
//! Nodes are keyed by index, never by name: real files repeat names (three.js's RobotExpressive
//! has a bone and a mesh node both called `Head`). Two world transforms are kept per node: the
//! full affine map (positions, including any scale in the hierarchy, e.g. FBX2glTF's 100×
//! armature) and the rotation-only chain `W = W_parent · R_local`, which is the frame bones turn
//! in. The two agree for uniform positive scales; non-uniform scale in a bone's ancestors would
//! shear its children under rotation, which no humanoid rig does on purpose.

use serde_json::Value;

use super::gltf_in::array;
use super::transform::{Affine, Trs};
use dancegen_motion::rotation::{Mat3, Quat};

/// Node hierarchy and rest pose of a glTF document.
#[derive(Debug, Clone)]
pub struct NodeTree {
    /// Node names (`""` when absent).
    pub names: Vec<String>,
    pub parents: Vec<Option<usize>>,
    pub children: Vec<Vec<usize>>,
    /// Rest (static) local transform of each node.
    pub rest: Vec<Trs>,
    /// Whether the node gives its transform as `matrix` (an animated node must use TRS).
    pub has_matrix: Vec<bool>,
    /// Whether the node carries a mesh or a camera (such a node is never a bone).
    pub has_content: Vec<bool>,
    /// Whether the node is a joint of some skin.
    pub is_joint: Vec<bool>,
    /// Every node, parents before children (depth first from the roots, in index order).
    pub order: Vec<usize>,
    /// Depth below its root (roots are 0).
    pub depth: Vec<usize>,
    /// Rest world transforms (affine) and rotation-only world frames.
    pub rest_world: Vec<Affine>,
    pub rest_frame: Vec<Mat3>,
}

impl NodeTree {
    /// Builds the hierarchy; `Err` says what is malformed (the caller adds the file name).
    pub fn from_json(json: &Value) -> Result<NodeTree, String> {
        let nodes = array(json, "nodes");
        let n = nodes.len();
        let mut names = Vec::with_capacity(n);
        let mut rest = Vec::with_capacity(n);
        let mut has_matrix = Vec::with_capacity(n);
        let mut has_content = Vec::with_capacity(n);
        let mut parents = vec![None; n];
        let mut children = vec![Vec::new(); n];
        for (i, node) in nodes.iter().enumerate() {
            names.push(
                node.get("name")
                    .and_then(Value::as_str)
                    .unwrap_or("")
                    .to_string(),
            );
            let (trs, m) = node_trs(node).map_err(|e| format!("node {i}: {e}"))?;
            rest.push(trs);
            has_matrix.push(m);
            has_content.push(node.get("mesh").is_some() || node.get("camera").is_some());
            for c in node
                .get("children")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                let c = c
                    .as_u64()
                    .map(|c| c as usize)
                    .filter(|&c| c < n)
                    .ok_or_else(|| format!("node {i} has a child that is not a node index"))?;
                if parents[c].is_some() || c == i {
                    return Err(format!(
                        "node {c} has more than one parent (the node graph must be a forest)"
                    ));
                }
                parents[c] = Some(i);
                children[i].push(c);
            }
        }
        let mut order = Vec::with_capacity(n);
        let mut depth = vec![0; n];
        for root in (0..n).filter(|&i| parents[i].is_none()) {
            let mut stack = vec![root];
            while let Some(k) = stack.pop() {
                order.push(k);
                for &c in children[k].iter().rev() {
                    depth[c] = depth[k] + 1;
                    stack.push(c);
                }
            }
        }
        if order.len() != n {
            return Err("the node hierarchy has a cycle".into());
        }
        let mut is_joint = vec![false; n];
        for (s, skin) in array(json, "skins").iter().enumerate() {
            for j in skin
                .get("joints")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                let j = j
                    .as_u64()
                    .map(|j| j as usize)
                    .filter(|&j| j < n)
                    .ok_or_else(|| format!("skin {s} lists a joint that is not a node index"))?;
                is_joint[j] = true;
            }
        }
        let mut tree = NodeTree {
            names,
            parents,
            children,
            rest,
            has_matrix,
            has_content,
            is_joint,
            order,
            depth,
            rest_world: Vec::new(),
            rest_frame: Vec::new(),
        };
        let (w, f) = tree.world(&tree.rest, &tree.order);
        tree.rest_world = w;
        tree.rest_frame = f;
        tree.check_rest_bounds()?;
        Ok(tree)
    }

    /// Every node's rest position is finite and within
    /// [`dancegen_motion::body_bounds::MAX_JOINT_DISTANCE_M`] of the origin (glTF is in
    /// metres): a character is a body on a floor, and farther values are garbage that would
    /// overflow the retargeting's float32 output.
    fn check_rest_bounds(&self) -> Result<(), String> {
        use dancegen_motion::body_bounds::{MAX_JOINT_DISTANCE_M, distance_from_origin};
        for k in 0..self.len() {
            let [x, y, z] = self.rest_position(k);
            let distance = distance_from_origin([x, y, z]);
            if !distance.is_finite() {
                return Err(format!(
                    "node {}: its rest position [{x:e}, {y:e}, {z:e}] is not finite",
                    self.label(k)
                ));
            }
            if distance > MAX_JOINT_DISTANCE_M {
                return Err(format!(
                    "node {}: its rest position is {distance:.4e} m from the origin; a character \
                     stays within {MAX_JOINT_DISTANCE_M} m (MAX_JOINT_DISTANCE_M)",
                    self.label(k)
                ));
            }
        }
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// World transforms for the given local transforms, evaluated in `order` (which must list
    /// parents before children).
    pub fn world(&self, local: &[Trs], order: &[usize]) -> (Vec<Affine>, Vec<Mat3>) {
        let mut world = vec![Affine::IDENTITY; self.len()];
        let mut frame = vec![Mat3::IDENTITY; self.len()];
        for &k in order {
            let a = local[k].to_affine();
            let r = local[k].rotation.to_mat3();
            match self.parents[k] {
                Some(p) => {
                    world[k] = world[p].mul(&a);
                    frame[k] = frame[p].mul(&r);
                }
                None => {
                    world[k] = a;
                    frame[k] = r;
                }
            }
        }
        (world, frame)
    }

    /// Rest world position of a node.
    pub fn rest_position(&self, k: usize) -> [f64; 3] {
        self.rest_world[k].translation
    }

    /// Whether `a` is a proper ancestor of `b`.
    pub fn is_ancestor(&self, a: usize, b: usize) -> bool {
        let mut k = self.parents[b];
        while let Some(p) = k {
            if p == a {
                return true;
            }
            k = self.parents[p];
        }
        false
    }

    /// The nodes strictly between `a` and its descendant `b`, top down (empty when `b` is not
    /// below `a`).
    pub fn between(&self, a: usize, b: usize) -> Vec<usize> {
        if !self.is_ancestor(a, b) {
            return Vec::new();
        }
        let mut out = Vec::new();
        let mut k = self.parents[b];
        while let Some(p) = k {
            if p == a {
                break;
            }
            out.push(p);
            k = self.parents[p];
        }
        out.reverse();
        out
    }

    /// Lowest common ancestor (a node counts as its own ancestor); `None` across roots.
    pub fn lca(&self, a: usize, b: usize) -> Option<usize> {
        let (mut a, mut b) = (a, b);
        while self.depth[a] > self.depth[b] {
            a = self.parents[a]?;
        }
        while self.depth[b] > self.depth[a] {
            b = self.parents[b]?;
        }
        while a != b {
            a = self.parents[a]?;
            b = self.parents[b]?;
        }
        Some(a)
    }

    /// The node and all its descendants.
    pub fn subtree(&self, k: usize) -> Vec<usize> {
        let mut out = vec![k];
        let mut i = 0;
        while i < out.len() {
            out.extend(self.children[out[i]].iter().copied());
            i += 1;
        }
        out
    }

    /// A readable label: the name, or `#index` for unnamed nodes.
    pub fn label(&self, k: usize) -> String {
        if self.names[k].is_empty() {
            format!("#{k}")
        } else {
            self.names[k].clone()
        }
    }
}

/// A node's local transform and whether it came from `matrix`.
fn node_trs(node: &Value) -> Result<(Trs, bool), String> {
    if let Some(m) = node.get("matrix") {
        let m = numbers::<16>(m).ok_or("matrix is not 16 finite numbers")?;
        return Ok((Trs::from_column_major(&m), true));
    }
    let translation = match node.get("translation") {
        Some(v) => numbers::<3>(v).ok_or("translation is not 3 finite numbers")?,
        None => [0.0; 3],
    };
    let rotation = match node.get("rotation") {
        Some(v) => {
            let q = numbers::<4>(v).ok_or("rotation is not 4 finite numbers")?;
            let q = Quat::new(q[3], q[0], q[1], q[2]);
            if q.norm() < 1e-6 {
                return Err("rotation is a zero quaternion".into());
            }
            q.normalize()
        }
        None => Quat::IDENTITY,
    };
    let scale = match node.get("scale") {
        Some(v) => numbers::<3>(v).ok_or("scale is not 3 finite numbers")?,
        None => [1.0; 3],
    };
    Ok((
        Trs {
            translation,
            rotation,
            scale,
        },
        false,
    ))
}

fn numbers<const N: usize>(v: &Value) -> Option<[f64; N]> {
    let a = v.as_array()?;
    if a.len() != N {
        return None;
    }
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().filter(|f| f.is_finite())?;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn hierarchy_queries_and_scaled_parent() {
        let doc = json!({"nodes": [
            {"name": "arm", "scale": [0.01, 0.01, 0.01], "children": [1]},
            {"name": "hips", "translation": [0.0, 100.0, 0.0], "children": [2, 3]},
            {"name": "a", "translation": [10.0, 0.0, 0.0]},
            {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,-50,0,1]}
        ], "skins": [{"joints": [1, 2, 3]}]});
        let t = NodeTree::from_json(&doc).unwrap();
        assert_eq!(t.order, vec![0, 1, 2, 3]);
        assert!((t.rest_position(1)[1] - 1.0).abs() < 1e-12);
        assert!((t.rest_position(2)[0] - 0.1).abs() < 1e-12);
        assert!((t.rest_position(3)[1] - 0.5).abs() < 1e-12);
        assert!(t.has_matrix[3] && !t.has_matrix[2]);
        assert_eq!(t.lca(2, 3), Some(1));
        assert_eq!(t.between(0, 2), vec![1]);
        assert!(t.is_ancestor(0, 3) && !t.is_ancestor(2, 3));
        assert_eq!(t.label(3), "#3");
    }

    #[test]
    fn malformed_hierarchies_are_errors() {
        let two_parents = json!({"nodes": [{"children": [2]}, {"children": [2]}, {}]});
        assert!(NodeTree::from_json(&two_parents).is_err());
        let cycle = json!({"nodes": [{"children": [1]}, {"children": [0]}]});
        assert!(NodeTree::from_json(&cycle).is_err());
        let bad = json!({"nodes": [{"rotation": [0, 0, 0]}]});
        assert!(NodeTree::from_json(&bad).unwrap_err().contains("node 0"));
    }

    #[test]
    fn nodes_beyond_the_distance_bound_are_refused() {
        let huge = json!({"nodes": [
            {"name": "root", "children": [1]},
            {"name": "hand", "translation": [1e308, 0, 0]}
        ]});
        let e = NodeTree::from_json(&huge).unwrap_err();
        assert!(
            e.starts_with("node hand:") && e.contains("1.0000e308 m"),
            "{e}"
        );
        // Each transform is finite; their product in world space is not.
        let overflow = json!({"nodes": [
            {"scale": [1e300, 1e300, 1e300], "children": [1]},
            {"name": "tip", "translation": [1e10, 0, 0]}
        ]});
        let e = NodeTree::from_json(&overflow).unwrap_err();
        assert!(
            e.starts_with("node tip:") && e.contains("not finite"),
            "{e}"
        );
        let far = json!({"nodes": [
            {"name": "hips", "translation": [0, 1, 0], "children": [1]},
            {"name": "hand", "translation": [0, 0, 2e4]}
        ]});
        let e = NodeTree::from_json(&far).unwrap_err();
        assert!(e.contains("hand") && e.contains("2.0000e4 m"), "{e}");
        let near = json!({"nodes": [{"translation": [9000, 0, 0]}]});
        assert!(NodeTree::from_json(&near).is_ok());
    }
}
