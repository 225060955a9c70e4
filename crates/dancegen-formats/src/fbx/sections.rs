//! The document-level sections around the objects: header, global settings (axes, units,
//! time), documents, definitions (object counts and property templates) and takes.

use super::tree::{
    CREATION_TIME, FILE_ID, Node, object_name, p, p_bool, p_color, p_color_a, p_double, p_enum,
    p_int, p_ktime, p_lcl, p_number, p_string, s,
};
use super::{UNIT_SCALE_FACTOR, time_mode};
use fbxcel::low::v7400::AttributeValue as A;

/// `GlobalSettings` axes: Y up, Z front, X right, all positive (FBX SDK
/// `FbxAxisSystem::MayaYUp`; axis indices 0 = X, 1 = Y, 2 = Z).
const UP_AXIS: i32 = 1;
const FRONT_AXIS: i32 = 2;
const COORD_AXIS: i32 = 0;
/// `TimeProtocol` `eDefaultProtocol` (FBX SDK `FbxTime::EProtocol`).
const TIME_PROTOCOL_DEFAULT: i32 = 2;
/// `RotationOrder` `eEulerXYZ` (0), also the template default.
pub(super) const EULER_XYZ: i32 = 0;

/// How many objects of each type the file holds (for `Definitions`).
#[derive(Debug, Default)]
pub(super) struct Counts {
    pub models: usize,
    pub node_attributes: usize,
    pub geometries: usize,
    pub materials: usize,
    pub deformers: usize,
    pub poses: usize,
    pub curve_nodes: usize,
    pub curves: usize,
}

/// The top-level nodes before `Objects`: header extension, file id, creation time, creator,
/// global settings, documents, references and definitions.
pub(super) fn preamble(
    fps: f32,
    last_time: i64,
    stack_name: &str,
    document_id: i64,
    counts: &Counts,
) -> Vec<Node> {
    vec![
        header_extension(),
        Node::value("FileId", FILE_ID.to_vec()),
        Node::value("CreationTime", s(CREATION_TIME)),
        Node::value("Creator", s(CREATOR)),
        global_settings(fps, last_time),
        documents(stack_name, document_id),
        Node::group("References", Vec::new()),
        definitions(counts),
    ]
}

/// `Creator` of the header and of the file.
const CREATOR: &str = "dancegen";

fn header_extension() -> Node {
    // Fixed, so the output does not depend on when it was written; the same instant as the
    // file's `CreationTime` (see `tree::FILE_ID`).
    let stamp = [
        ("Version", 1000),
        ("Year", 1970),
        ("Month", 1),
        ("Day", 1),
        ("Hour", 10),
        ("Minute", 0),
        ("Second", 0),
        ("Millisecond", 0),
    ];
    let app = |prefix: &str| {
        vec![
            p(prefix, "Compound", "", "", []),
            p_string(&format!("{prefix}|ApplicationVendor"), CREATOR),
            p_string(&format!("{prefix}|ApplicationName"), CREATOR),
            p_string(
                &format!("{prefix}|ApplicationVersion"),
                env!("CARGO_PKG_VERSION"),
            ),
            p(
                &format!("{prefix}|DateTime_GMT"),
                "DateTime",
                "",
                "",
                [s("01/01/1970 10:00:00.000")],
            ),
        ]
    };
    let mut scene_props = app("Original");
    scene_props.extend(app("LastSaved"));
    Node::group(
        "FBXHeaderExtension",
        vec![
            Node::value("FBXHeaderVersion", 1003i32),
            Node::value("FBXVersion", 7400i32),
            Node::value("EncryptionType", 0i32),
            Node::group(
                "CreationTimeStamp",
                stamp
                    .iter()
                    .map(|&(name, v)| Node::value(name, v))
                    .collect(),
            ),
            Node::value("Creator", s(CREATOR)),
            Node::with(
                "SceneInfo",
                vec![object_name("GlobalInfo", "SceneInfo"), s("UserData")],
                vec![
                    Node::value("Type", s("UserData")),
                    Node::value("Version", 100i32),
                    Node::group(
                        "MetaData",
                        vec![
                            Node::value("Version", 100i32),
                            Node::value("Title", s("")),
                            Node::value("Subject", s("")),
                            Node::value("Author", s("")),
                            Node::value("Keywords", s("")),
                            Node::value("Revision", s("")),
                            Node::value("Comment", s("")),
                        ],
                    ),
                    Node::group("Properties70", scene_props),
                ],
            ),
        ],
    )
}

fn global_settings(fps: f32, last_time: i64) -> Node {
    Node::group(
        "GlobalSettings",
        vec![
            Node::value("Version", 1000i32),
            Node::group(
                "Properties70",
                vec![
                    p_int("UpAxis", UP_AXIS),
                    p_int("UpAxisSign", 1),
                    p_int("FrontAxis", FRONT_AXIS),
                    p_int("FrontAxisSign", 1),
                    p_int("CoordAxis", COORD_AXIS),
                    p_int("CoordAxisSign", 1),
                    p_int("OriginalUpAxis", UP_AXIS),
                    p_int("OriginalUpAxisSign", 1),
                    p_double("UnitScaleFactor", UNIT_SCALE_FACTOR),
                    p_double("OriginalUnitScaleFactor", UNIT_SCALE_FACTOR),
                    p_color("AmbientColor", [0.0; 3]),
                    p_string("DefaultCamera", "Producer Perspective"),
                    p_enum("TimeMode", time_mode(fps)),
                    p_enum("TimeProtocol", TIME_PROTOCOL_DEFAULT),
                    p_enum("SnapOnFrameMode", 0),
                    p_ktime("TimeSpanStart", 0),
                    p_ktime("TimeSpanStop", last_time),
                    p_double("CustomFrameRate", f64::from(fps)),
                    p("TimeMarker", "Compound", "", "", []),
                    p_int("CurrentTimeMarker", -1),
                ],
            ),
        ],
    )
}

fn documents(stack_name: &str, document_id: i64) -> Node {
    Node::group(
        "Documents",
        vec![
            Node::value("Count", 1i32),
            Node::with(
                "Document",
                vec![document_id.into(), s("Scene"), s("Scene")],
                vec![
                    Node::group(
                        "Properties70",
                        vec![
                            p("SourceObject", "object", "", "", []),
                            p_string("ActiveAnimStackName", stack_name),
                        ],
                    ),
                    // The scene root's id, which top-level objects connect to.
                    Node::value("RootNode", 0i64),
                ],
            ),
        ],
    )
}

/// `Definitions`: how many objects of each type the file holds, with property templates (the
/// defaults of properties an object does not list) for the types whose defaults readers use.
fn definitions(c: &Counts) -> Node {
    let object_type = |name: &str, count: usize, template: Option<(&str, Vec<Node>)>| {
        let mut children = vec![Node::value("Count", count as i32)];
        if let Some((class, props)) = template {
            children.push(Node::with(
                "PropertyTemplate",
                vec![s(class)],
                vec![Node::group("Properties70", props)],
            ));
        }
        Node::with("ObjectType", vec![s(name)], children)
    };
    let types = vec![
        object_type("GlobalSettings", 1, None),
        object_type(
            "Model",
            c.models,
            Some((
                "FbxNode",
                vec![
                    p_enum("QuaternionInterpolate", 0),
                    p_bool("RotationActive", false),
                    p_enum("RotationOrder", EULER_XYZ),
                    p_enum("InheritType", 0),
                    p_int("DefaultAttributeIndex", -1),
                    p_lcl("Lcl Translation", [0.0; 3]),
                    p_lcl("Lcl Rotation", [0.0; 3]),
                    p_lcl("Lcl Scaling", [1.0; 3]),
                    p("Visibility", "Visibility", "", "A", [1.0f64.into()]),
                    p(
                        "Visibility Inheritance",
                        "Visibility Inheritance",
                        "",
                        "",
                        [1i32.into()],
                    ),
                ],
            )),
        ),
        object_type(
            "NodeAttribute",
            c.node_attributes,
            Some((
                "FbxSkeleton",
                vec![
                    p_color("Color", [0.8, 0.8, 0.8]),
                    p_double("Size", 100.0),
                    p("LimbLength", "double", "Number", "H", [1.0f64.into()]),
                ],
            )),
        ),
        object_type(
            "Geometry",
            c.geometries,
            Some((
                "FbxMesh",
                vec![
                    p_color("Color", [0.8, 0.8, 0.8]),
                    p(
                        "BBoxMin",
                        "Vector3D",
                        "Vector",
                        "",
                        [0.0f64, 0.0, 0.0].map(A::F64),
                    ),
                    p(
                        "BBoxMax",
                        "Vector3D",
                        "Vector",
                        "",
                        [0.0f64, 0.0, 0.0].map(A::F64),
                    ),
                    p_bool("Primary Visibility", true),
                    p_bool("Casts Shadows", true),
                    p_bool("Receive Shadows", true),
                ],
            )),
        ),
        object_type(
            "Material",
            c.materials,
            Some((
                "FbxSurfaceLambert",
                vec![
                    p_string("ShadingModel", "Lambert"),
                    p_bool("MultiLayer", false),
                    p_color_a("EmissiveColor", [0.0; 3]),
                    p_number("EmissiveFactor", 1.0),
                    p_color_a("AmbientColor", [0.2, 0.2, 0.2]),
                    p_number("AmbientFactor", 1.0),
                    p_color_a("DiffuseColor", [0.8, 0.8, 0.8]),
                    p_number("DiffuseFactor", 1.0),
                    p_color_a("TransparentColor", [0.0; 3]),
                    p_number("TransparencyFactor", 0.0),
                ],
            )),
        ),
        object_type("Deformer", c.deformers, None),
        object_type("Pose", c.poses, None),
        object_type(
            "AnimationStack",
            1,
            Some((
                "FbxAnimStack",
                vec![
                    p_string("Description", ""),
                    p_ktime("LocalStart", 0),
                    p_ktime("LocalStop", 0),
                    p_ktime("ReferenceStart", 0),
                    p_ktime("ReferenceStop", 0),
                ],
            )),
        ),
        object_type(
            "AnimationLayer",
            1,
            Some((
                "FbxAnimLayer",
                vec![
                    p_number("Weight", 100.0),
                    p_bool("Mute", false),
                    p_bool("Solo", false),
                    p_bool("Lock", false),
                    p_color("Color", [0.8, 0.8, 0.8]),
                    p_enum("BlendMode", 0),
                    p_enum("RotationAccumulationMode", 0),
                    p_enum("ScaleAccumulationMode", 0),
                ],
            )),
        ),
        object_type(
            "AnimationCurveNode",
            c.curve_nodes,
            Some(("FbxAnimCurveNode", vec![p("d", "Compound", "", "", [])])),
        ),
        object_type("AnimationCurve", c.curves, None),
    ];
    let total = 1
        + c.models
        + c.node_attributes
        + c.geometries
        + c.materials
        + c.deformers
        + c.poses
        + 2
        + c.curve_nodes
        + c.curves;
    let mut children = vec![
        Node::value("Version", 100i32),
        Node::value("Count", total as i32),
    ];
    children.extend(types);
    Node::group("Definitions", children)
}

pub(super) fn takes(name: &str, last_time: i64) -> Node {
    Node::group(
        "Takes",
        vec![
            Node::value("Current", s(name)),
            Node::with(
                "Take",
                vec![s(name)],
                vec![
                    Node::value("FileName", s(&format!("{name}.tak"))),
                    Node::leaf("LocalTime", [0i64, last_time]),
                    Node::leaf("ReferenceTime", [0i64, last_time]),
                ],
            ),
        ],
    )
}
