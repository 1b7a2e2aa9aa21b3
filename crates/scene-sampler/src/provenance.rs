//! Where a scene's faces came from, so that an output (the bake, `gcr solve --mesh`) can be
//! written back in the shape of its input.
//!
//! Every [`Face`](crate::Face) has a [`part`](crate::Face::part): an index into
//! [`Scene::parts`](crate::Scene::parts). A [`Part`] is one input primitive of one node instance
//! (glTF) or one object (OBJ, built-ins, [`Scene::new`](crate::Scene::new) callers). A scene
//! loaded from glTF also carries a [`GltfSource`] ([`Scene::gltf`](crate::Scene::gltf)): the
//! document's node tree, mesh and material names, as given, without any geometry (the geometry
//! is in the faces, in world coordinates).

use glam::DMat4;

/// One input primitive of one node instance, or one object of a file without a node tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// Object index (into [`Scene::objects`](crate::Scene::objects)); for glTF the node instance.
    pub object: u32,
    /// glTF node (into [`GltfSource::nodes`]); `None` without a node tree.
    pub node: Option<u32>,
    /// glTF mesh (into [`GltfSource::meshes`]); `None` without a node tree.
    pub mesh: Option<u32>,
    /// Index of the primitive in its glTF mesh; 0 without a node tree.
    pub primitive: u32,
}

impl Part {
    /// The part that is a whole object (OBJ, built-ins): no node, no mesh, primitive 0.
    pub fn of_object(object: u32) -> Self {
        Self {
            object,
            node: None,
            mesh: None,
            primitive: 0,
        }
    }
}

/// A glTF node's local transform as the file gave it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NodeTransform {
    /// `matrix`: column-major 4 × 4.
    Matrix([[f32; 4]; 4]),
    /// `translation`, `rotation` (unit quaternion x, y, z, w) and `scale` (absent ones at their
    /// defaults: 0, identity, 1).
    Trs {
        /// Translation.
        translation: [f32; 3],
        /// Rotation quaternion `[x, y, z, w]`.
        rotation: [f32; 4],
        /// Scale.
        scale: [f32; 3],
    },
}

impl NodeTransform {
    /// Whether this is the identity (no transform written).
    pub fn is_identity(&self) -> bool {
        match self {
            NodeTransform::Matrix(m) => {
                *m == [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            }
            NodeTransform::Trs {
                translation,
                rotation,
                scale,
            } => {
                *translation == [0.0; 3] && *rotation == [0.0, 0.0, 0.0, 1.0] && *scale == [1.0; 3]
            }
        }
    }
}

/// One node of the source document.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfNode {
    /// The node's name, if it has one.
    pub name: Option<String>,
    /// Local transform as given.
    pub transform: NodeTransform,
    /// Child nodes (indices into [`GltfSource::nodes`]).
    pub children: Vec<u32>,
    /// The node's mesh (into [`GltfSource::meshes`]).
    pub mesh: Option<u32>,
    /// The world transform the loader applied to this node's mesh (composed in f64 from the
    /// local matrices); `None` for a node outside the loaded scene.
    pub world: Option<DMat4>,
}

/// One mesh of the source document.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMesh {
    /// The mesh's name, if it has one.
    pub name: Option<String>,
    /// Per primitive, its material (into [`GltfSource::materials`]); `None` is glTF's default
    /// material.
    pub primitives: Vec<Option<u32>>,
}

/// One material of the source document.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    /// The material's name, if it has one.
    pub name: Option<String>,
    /// `pbrMetallicRoughness.baseColorFactor` as given (before ρ's clamping).
    pub base_color: [f32; 4],
}

/// What a writer needs to give an output the input's glTF structure: every node of the document
/// (by index, in file order), the roots of the scene that was loaded, every mesh and material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfSource {
    /// The loaded scene's name, if it has one.
    pub scene_name: Option<String>,
    /// Root nodes of the loaded scene.
    pub roots: Vec<u32>,
    /// All nodes of the document.
    pub nodes: Vec<GltfNode>,
    /// All meshes of the document.
    pub meshes: Vec<GltfMesh>,
    /// All materials of the document.
    pub materials: Vec<GltfMaterial>,
}

impl GltfSource {
    /// Reads the structure of `doc`, the world transforms left unset (the loader sets them for
    /// the nodes of the scene it loads).
    pub(crate) fn of_document(doc: &gltf::Document, scene: &gltf::Scene) -> Self {
        let nodes = doc
            .nodes()
            .map(|n| GltfNode {
                name: n.name().map(String::from),
                transform: match n.transform() {
                    gltf::scene::Transform::Matrix { matrix } => NodeTransform::Matrix(matrix),
                    gltf::scene::Transform::Decomposed {
                        translation,
                        rotation,
                        scale,
                    } => NodeTransform::Trs {
                        translation,
                        rotation,
                        scale,
                    },
                },
                children: n.children().map(|c| c.index() as u32).collect(),
                mesh: n.mesh().map(|m| m.index() as u32),
                world: None,
            })
            .collect();
        let meshes = doc
            .meshes()
            .map(|m| GltfMesh {
                name: m.name().map(String::from),
                primitives: m
                    .primitives()
                    .map(|p| p.material().index().map(|i| i as u32))
                    .collect(),
            })
            .collect();
        let materials = doc
            .materials()
            .map(|m| GltfMaterial {
                name: m.name().map(String::from),
                base_color: m.pbr_metallic_roughness().base_color_factor(),
            })
            .collect();
        Self {
            scene_name: scene.name().map(String::from),
            roots: scene.nodes().map(|n| n.index() as u32).collect(),
            nodes,
            meshes,
            materials,
        }
    }

    /// How many nodes of the loaded scene use mesh `mesh`.
    pub fn instances(&self, mesh: u32) -> usize {
        self.nodes
            .iter()
            .filter(|n| n.mesh == Some(mesh) && n.world.is_some())
            .count()
    }
}
