//! The objects of the scene and their connections, assembled as a [`Node`] tree (see the parent
//! module for the conventions they follow); [`sections`](super::sections) adds the rest of the
//! file around them.

use super::euler::continuous_euler_xyz_degrees;
use super::sections::{self, Counts, EULER_XYZ};
use super::tree::{
    Node, object_name, p_bool, p_color_a, p_enum, p_int, p_ktime, p_lcl, p_number, s,
};
use super::{FbxInputError, FbxOptions};
use crate::capsule_mesh::build_capsule_mesh;
use crate::gltf::{DancerAnimation, EXTRA_DANCER_COLORS};
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::Skeleton;
use dancegen_motion::vec3::add;

/// `KeyAttrFlags` of every key: `eInterpolationLinear` (FBX SDK `FbxAnimCurveDef`, 0x4; ufbx
/// reads keys with neither the constant (0x2) nor the cubic (0x8) bit as linear).
const KEY_LINEAR: i32 = 0x0000_0004;

/// `KeyAttrDataFloat` of a key: right slope, next left slope, packed tangent weights, packed
/// velocities. Slopes are unused by linear keys; the weights hold the FBX SDK's default 1/3 on
/// both sides (0.3333 as two 16-bit fixed-point halves, `0x0D05_0D05`, the `218434821` seen in
/// ASCII files).
const KEY_ATTR_DATA: [u32; 4] = [0, 0, 0x0D05_0D05, 0];

/// `Model` node version written by the FBX SDK 2014–2020 (FBX 7.4).
const MODEL_VERSION: i32 = 232;
/// `GeometryVersion` of FBX 7.4 meshes.
const GEOMETRY_VERSION: i32 = 124;
/// `KeyVer` of FBX 7.4 animation curves.
const CURVE_KEY_VERSION: i32 = 4009;
/// `InheritType` `eInheritRSrs` (1): parent scale applied after the child's rotation — Maya's
/// and Blender's choice; every scale here is 1, so the mode does not change any transform.
const INHERIT_RSRS: i32 = 1;

/// Object ids: plain counters (any distinct non-zero 64-bit numbers will do; 0 is the scene
/// root), which keeps the output deterministic.
struct Ids(i64);

impl Ids {
    fn next(&mut self) -> i64 {
        self.0 += 1;
        self.0
    }
}

/// An object-object (`OO`) connection, child first.
fn oo(child: i64, parent: i64) -> Node {
    Node::with("C", vec![s("OO"), child.into(), parent.into()], Vec::new())
}

/// An object-property (`OP`) connection: `child` drives `property` of `parent`.
fn op(child: i64, parent: i64, property: &str) -> Node {
    Node::with(
        "C",
        vec![s("OP"), child.into(), parent.into(), s(property)],
        Vec::new(),
    )
}

/// Column-major 4×4 translation, the matrix layout of FBX's `Matrix`, `Transform` and
/// `TransformLink`.
fn translation_matrix(t: [f64; 3]) -> Vec<f64> {
    vec![
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, t[0], t[1], t[2], 1.0,
    ]
}

/// A model node with its static local transform (animated channels override it).
fn model(id: i64, name: &str, kind: &str, translation: [f64; 3]) -> Node {
    Node::with(
        "Model",
        vec![id.into(), object_name(name, "Model"), s(kind)],
        vec![
            Node::value("Version", MODEL_VERSION),
            Node::group(
                "Properties70",
                vec![
                    p_bool("RotationActive", true),
                    p_enum("InheritType", INHERIT_RSRS),
                    p_enum("RotationOrder", EULER_XYZ),
                    p_int("DefaultAttributeIndex", 0),
                    p_lcl("Lcl Translation", translation),
                    p_lcl("Lcl Rotation", [0.0; 3]),
                    p_lcl("Lcl Scaling", [1.0; 3]),
                ],
            ),
            Node::value("Shading", true),
            Node::value("Culling", s("CullingOff")),
        ],
    )
}

/// The objects and connections collected so far, and their counts.
#[derive(Default)]
struct Content {
    objects: Vec<Node>,
    connections: Vec<Node>,
    counts: Counts,
}

/// The body's arrays, the same for every dancer (each dancer still needs its own `Geometry`:
/// the skin hangs off the geometry and binds it to that dancer's joints).
struct Body {
    /// Rest world position of each joint (its bind matrix is the translation to it).
    rest: Vec<[f64; 3]>,
    vertices: Vec<f64>,
    /// Triangles; the last index of each polygon is stored as `-(i + 1)` to close it.
    polygon_vertex_index: Vec<i32>,
    /// One normal per polygon corner.
    normals: Vec<f64>,
    /// Vertices each joint moves.
    cluster_vertices: Vec<Vec<i32>>,
}

impl Body {
    fn new(skeleton: &Skeleton, opts: &FbxOptions) -> Result<Body, FbxInputError> {
        // Rest world positions (rest rotations are identity), as gltf.rs.
        let (parents, offsets) = (skeleton.parents(), skeleton.offsets());
        let mut rest: Vec<[f64; 3]> = Vec::with_capacity(skeleton.len());
        for j in 0..skeleton.len() {
            rest.push(match parents[j] {
                None => offsets[j],
                Some(p) => add(rest[p], offsets[j]),
            });
        }
        let shape = opts.capsule_shape();
        let mesh = build_capsule_mesh(skeleton, &rest, shape);
        if mesh.indices.len() > i32::MAX as usize {
            let n = mesh.indices.len();
            return Err(FbxInputError::TooLarge(format!("{n} triangle corners")));
        }
        let mut cluster_vertices: Vec<Vec<i32>> = vec![Vec::new(); skeleton.len()];
        for (v, &j) in mesh.joints.iter().enumerate() {
            cluster_vertices[j as usize].push(v as i32);
        }
        Ok(Body {
            rest,
            vertices: mesh.positions.iter().map(|&v| f64::from(v)).collect(),
            polygon_vertex_index: mesh
                .indices
                .chunks_exact(3)
                .flat_map(|t| [t[0] as i32, t[1] as i32, !(t[2] as i32)])
                .collect(),
            normals: mesh
                .indices
                .iter()
                .flat_map(|&i| {
                    let k = i as usize * 3;
                    [0, 1, 2].map(|c| f64::from(mesh.normals[k + c]))
                })
                .collect(),
            cluster_vertices,
        })
    }
}

/// Object names of one dancer: unprefixed when alone, `dancer{d}/…` in a group.
struct Names {
    dancer: usize,
    many: bool,
}

impl Names {
    fn of(&self, what: &str) -> String {
        if self.many {
            format!("dancer{}/{what}", self.dancer)
        } else {
            what.to_string()
        }
    }

    /// The armature `Null`.
    fn armature(&self) -> String {
        if self.many {
            format!("dancer{}", self.dancer)
        } else {
            "armature".to_string()
        }
    }
}

/// The file's top-level nodes for validated inputs; `times` are the frames' KTimes.
pub(super) fn build(
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    times: &[i64],
    opts: &FbxOptions,
) -> Result<Vec<Node>, FbxInputError> {
    let body = Body::new(skeleton, opts)?;
    let last_time = times[times.len() - 1];
    let mut ids = Ids(1_000_000);
    let mut c = Content::default();

    // One stack and layer animate everyone.
    let stack_id = ids.next();
    let layer_id = ids.next();
    c.objects.push(Node::with(
        "AnimationStack",
        vec![
            stack_id.into(),
            object_name(&opts.animation_name, "AnimStack"),
            s(""),
        ],
        vec![Node::group(
            "Properties70",
            vec![
                p_ktime("LocalStart", 0),
                p_ktime("LocalStop", last_time),
                p_ktime("ReferenceStart", 0),
                p_ktime("ReferenceStop", last_time),
            ],
        )],
    ));
    // The layer's properties are the FBX SDK's defaults, written anyway: assimp reads an
    // AnimationLayer only with a `{ … }` scope, and without one dropped the whole animation
    // ("Animations: 0").
    c.objects.push(Node::with(
        "AnimationLayer",
        vec![
            layer_id.into(),
            object_name("BaseLayer", "AnimLayer"),
            s(""),
        ],
        vec![Node::group("Properties70", vec![p_number("Weight", 100.0)])],
    ));
    c.connections.push(oo(layer_id, stack_id));

    for (d, dancer) in dancers.iter().enumerate() {
        let names = Names {
            dancer: d,
            many: dancers.len() > 1,
        };
        let (null_id, joint_ids) = add_skeleton(&mut c, &mut ids, skeleton, &names);
        let color = if d == 0 {
            opts.base_color
        } else {
            EXTRA_DANCER_COLORS[(d - 1) % EXTRA_DANCER_COLORS.len()]
        };
        let body_ids = BodyIds {
            null: null_id,
            joints: &joint_ids,
        };
        add_body(&mut c, &mut ids, skeleton, &body, &names, body_ids, color);
        add_animation(&mut c, &mut ids, layer_id, dancer, times, &joint_ids);
    }

    let document_id = ids.next();
    let mut top = sections::preamble(fps, last_time, &opts.animation_name, document_id, &c.counts);
    top.push(Node::group("Objects", c.objects));
    top.push(Node::group("Connections", c.connections));
    top.push(sections::takes(&opts.animation_name, last_time));
    Ok(top)
}

/// The armature `Null` (at the origin, under the scene root) and one `LimbNode` model with a
/// `Skeleton` attribute per joint. Returns the ids of the null and of the joints.
fn add_skeleton(
    c: &mut Content,
    ids: &mut Ids,
    skeleton: &Skeleton,
    names: &Names,
) -> (i64, Vec<i64>) {
    let null_id = ids.next();
    c.objects
        .push(model(null_id, &names.armature(), "Null", [0.0; 3]));
    c.connections.push(oo(null_id, 0));
    c.counts.models += 1;
    let mut joint_ids: Vec<i64> = Vec::with_capacity(skeleton.len());
    for (j, name) in skeleton.names().iter().enumerate() {
        let (id, attr_id) = (ids.next(), ids.next());
        let name = names.of(name);
        c.objects.push(Node::with(
            "NodeAttribute",
            vec![
                attr_id.into(),
                object_name(&name, "NodeAttribute"),
                s("LimbNode"),
            ],
            vec![Node::value("TypeFlags", s("Skeleton"))],
        ));
        c.objects
            .push(model(id, &name, "LimbNode", skeleton.offsets()[j]));
        c.connections.push(oo(attr_id, id));
        let parent = skeleton.parents()[j].map_or(null_id, |p| joint_ids[p]);
        c.connections.push(oo(id, parent));
        c.counts.models += 1;
        c.counts.node_attributes += 1;
        joint_ids.push(id);
    }
    (null_id, joint_ids)
}

/// The models a dancer's body attaches to.
#[derive(Clone, Copy)]
struct BodyIds<'a> {
    null: i64,
    joints: &'a [i64],
}

/// The body: mesh model (under the armature), geometry, material, skin with one cluster per
/// joint, and the bind pose.
fn add_body(
    c: &mut Content,
    ids: &mut Ids,
    skeleton: &Skeleton,
    body: &Body,
    names: &Names,
    to: BodyIds<'_>,
    color: [f32; 4],
) {
    let name = names.of("body");
    let (mesh_model_id, geometry_id, material_id) = (ids.next(), ids.next(), ids.next());
    c.objects
        .push(model(mesh_model_id, &name, "Mesh", [0.0; 3]));
    c.connections.push(oo(mesh_model_id, to.null));
    c.counts.models += 1;

    let layer_element = |kind: &str| {
        Node::group(
            "LayerElement",
            vec![
                Node::value("Type", s(kind)),
                Node::value("TypedIndex", 0i32),
            ],
        )
    };
    c.objects.push(Node::with(
        "Geometry",
        vec![
            geometry_id.into(),
            object_name(&name, "Geometry"),
            s("Mesh"),
        ],
        vec![
            Node::value("GeometryVersion", GEOMETRY_VERSION),
            Node::value("Vertices", body.vertices.clone()),
            Node::value("PolygonVertexIndex", body.polygon_vertex_index.clone()),
            Node::with(
                "LayerElementNormal",
                vec![0i32.into()],
                vec![
                    Node::value("Version", 101i32),
                    Node::value("Name", s("")),
                    Node::value("MappingInformationType", s("ByPolygonVertex")),
                    Node::value("ReferenceInformationType", s("Direct")),
                    Node::value("Normals", body.normals.clone()),
                ],
            ),
            Node::with(
                "LayerElementMaterial",
                vec![0i32.into()],
                vec![
                    Node::value("Version", 101i32),
                    Node::value("Name", s("")),
                    Node::value("MappingInformationType", s("AllSame")),
                    Node::value("ReferenceInformationType", s("IndexToDirect")),
                    Node::value("Materials", vec![0i32]),
                ],
            ),
            Node::with(
                "Layer",
                vec![0i32.into()],
                vec![
                    Node::value("Version", 100i32),
                    layer_element("LayerElementNormal"),
                    layer_element("LayerElementMaterial"),
                ],
            ),
        ],
    ));
    c.connections.push(oo(geometry_id, mesh_model_id));
    c.counts.geometries += 1;

    let rgb = [0, 1, 2].map(|k| f64::from(color[k]));
    c.objects.push(Node::with(
        "Material",
        vec![material_id.into(), object_name(&name, "Material"), s("")],
        vec![
            Node::value("Version", 102i32),
            Node::value("ShadingModel", s("lambert")),
            Node::value("MultiLayer", 0i32),
            Node::group(
                "Properties70",
                vec![
                    p_color_a("DiffuseColor", rgb),
                    p_number("DiffuseFactor", 1.0),
                ],
            ),
        ],
    ));
    c.connections.push(oo(material_id, mesh_model_id));
    c.counts.materials += 1;

    // Skin: one cluster per joint binding the vertices of the capsules it moves (weight 1).
    // `TransformLink` is the joint's bind (rest world) matrix, `Transform` the mesh's bind
    // matrix relative to the joint (the mesh sits at the origin, so its inverse).
    let skin_id = ids.next();
    c.objects.push(Node::with(
        "Deformer",
        vec![skin_id.into(), object_name(&name, "Deformer"), s("Skin")],
        vec![
            Node::value("Version", 101i32),
            Node::value("Link_DeformAcuracy", 50.0f64),
            Node::value("SkinningType", s("Linear")),
        ],
    ));
    c.connections.push(oo(skin_id, geometry_id));
    c.counts.deformers += 1;
    for (j, joint) in skeleton.names().iter().enumerate() {
        let cluster_id = ids.next();
        let vertices = &body.cluster_vertices[j];
        let mut children = vec![
            Node::value("Version", 100i32),
            Node::leaf("UserData", [s(""), s("")]),
        ];
        // Joints that move no vertex (leaves) get no index arrays, as the FBX SDK writes them.
        if !vertices.is_empty() {
            children.push(Node::value("Indexes", vertices.clone()));
            children.push(Node::value("Weights", vec![1.0f64; vertices.len()]));
        }
        let rest = body.rest[j];
        children.push(Node::value(
            "Transform",
            translation_matrix(rest.map(|v| -v)),
        ));
        children.push(Node::value("TransformLink", translation_matrix(rest)));
        c.objects.push(Node::with(
            "Deformer",
            vec![
                cluster_id.into(),
                object_name(&names.of(joint), "SubDeformer"),
                s("Cluster"),
            ],
            children,
        ));
        c.connections.push(oo(cluster_id, skin_id));
        c.connections.push(oo(to.joints[j], cluster_id));
        c.counts.deformers += 1;
    }

    // Bind pose: the world matrix of every node at bind time.
    let pose_node = |id: i64, m: Vec<f64>| {
        Node::group(
            "PoseNode",
            vec![Node::value("Node", id), Node::value("Matrix", m)],
        )
    };
    let mut pose = vec![
        Node::value("Type", s("BindPose")),
        Node::value("Version", 100i32),
        Node::value("NbPoseNodes", (to.joints.len() + 2) as i32),
        pose_node(to.null, translation_matrix([0.0; 3])),
    ];
    for (&id, &rest) in to.joints.iter().zip(&body.rest) {
        pose.push(pose_node(id, translation_matrix(rest)));
    }
    pose.push(pose_node(mesh_model_id, translation_matrix([0.0; 3])));
    c.objects.push(Node::with(
        "Pose",
        vec![
            ids.next().into(),
            object_name(&names.of("BindPose"), "Pose"),
            s("BindPose"),
        ],
        pose,
    ));
    c.counts.poses += 1;
}

/// Per joint an `R` curve node on `Lcl Rotation` (continuous XYZ Euler degrees), and on the
/// root a `T` curve node on `Lcl Translation` (the pelvis world position).
fn add_animation(
    c: &mut Content,
    ids: &mut Ids,
    layer: i64,
    dancer: &DancerAnimation<'_>,
    times: &[i64],
    joint_ids: &[i64],
) {
    let (frames, joints) = (times.len(), joint_ids.len());
    let rot = dancer.local_rotations_axis_angle;
    for (j, &joint) in joint_ids.iter().enumerate() {
        let euler = continuous_euler_xyz_degrees((0..frames).map(|f| {
            let a = &rot[(f * joints + j) * 3..][..3];
            Mat3::from_axis_angle([a[0], a[1], a[2]].map(f64::from))
        }));
        let axes = [0, 1, 2].map(|k| euler.iter().map(|e| e[k] as f32).collect());
        let target = CurveTarget {
            layer,
            model: joint,
            property: "Lcl Rotation",
        };
        add_curve_node(c, ids, target, "R", times, axes);
    }
    let tr = dancer.root_translation;
    let axes = [0, 1, 2].map(|k| (0..frames).map(|f| tr[f * 3 + k]).collect());
    let target = CurveTarget {
        layer,
        model: joint_ids[0],
        property: "Lcl Translation",
    };
    add_curve_node(c, ids, target, "T", times, axes);
}

/// What a curve node animates.
struct CurveTarget {
    layer: i64,
    model: i64,
    property: &'static str,
}

/// A curve node `name` with one linear curve per axis (`d|X`, `d|Y`, `d|Z`) keyed at `times`.
fn add_curve_node(
    c: &mut Content,
    ids: &mut Ids,
    target: CurveTarget,
    name: &str,
    times: &[i64],
    axes: [Vec<f32>; 3],
) {
    let node_id = ids.next();
    let channels = ["d|X", "d|Y", "d|Z"];
    c.objects.push(Node::with(
        "AnimationCurveNode",
        vec![node_id.into(), object_name(name, "AnimCurveNode"), s("")],
        vec![Node::group(
            "Properties70",
            (0..3)
                .map(|k| p_number(channels[k], f64::from(axes[k][0])))
                .collect(),
        )],
    ));
    c.connections.push(oo(node_id, target.layer));
    c.connections
        .push(op(node_id, target.model, target.property));
    c.counts.curve_nodes += 1;
    for (values, channel) in axes.into_iter().zip(channels) {
        let curve_id = ids.next();
        c.objects.push(Node::with(
            "AnimationCurve",
            vec![curve_id.into(), object_name("", "AnimCurve"), s("")],
            vec![
                Node::value("Default", f64::from(values[0])),
                Node::value("KeyVer", CURVE_KEY_VERSION),
                Node::value("KeyTime", times.to_vec()),
                Node::value("KeyValueFloat", values),
                Node::value("KeyAttrFlags", vec![KEY_LINEAR]),
                Node::value(
                    "KeyAttrDataFloat",
                    KEY_ATTR_DATA.map(f32::from_bits).to_vec(),
                ),
                // One flags/data entry shared by all keys (a run-length count).
                Node::value("KeyAttrRefCount", vec![times.len() as i32]),
            ],
        ));
        c.connections.push(op(curve_id, node_id, channel));
        c.counts.curves += 1;
    }
}
