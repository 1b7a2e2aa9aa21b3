"""The scene shared by mitsuba_field.py and mitsuba_image.py: triangles with a diffuse ρ and an
emitted radiance Ke (`x0 y0 z0 x1 y1 z1 x2 y2 z2 rho_r rho_g rho_b Ke_r Ke_g Ke_b` per row) as one
Mitsuba 3 mesh per material, in a scene dict with the `path` integrator at unbounded depth.
The caller imports mitsuba and sets the variant first."""
import mitsuba as mi
import numpy as np


def scene_dict(tri):
    """The rows of `tri` (N × 15) as a Mitsuba scene dict without a sensor."""
    groups = {}
    for row in tri:
        groups.setdefault(tuple(row[9:15]), []).append(row[:9])
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": -1}}
    for k, (mat, rows) in enumerate(groups.items()):
        v = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
        props = mi.Properties()
        props["bsdf"] = mi.load_dict(
            {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(mat[:3])}}
        )
        if max(mat[3:]) > 0:
            props["emitter"] = mi.load_dict(
                {"type": "area", "radiance": {"type": "rgb", "value": list(mat[3:])}}
            )
        mesh = mi.Mesh(
            f"m{k}",
            vertex_count=len(v),
            face_count=len(rows),
            has_vertex_normals=False,
            has_vertex_texcoords=False,
            props=props,
        )
        params = mi.traverse(mesh)
        params["vertex_positions"] = v.ravel().tolist()
        params["faces"] = list(range(len(v)))
        params.update()
        scene[f"mesh{k}"] = mesh
    return scene
