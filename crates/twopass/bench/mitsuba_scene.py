"""A twopass scene file as a Mitsuba 3 scene, for the benchmark scripts beside this file.

What is converted, and how:

- camera: `perspective` sensor, vertical field of view 2 atan(film height / 2 / focal length),
  `look_at` with the file's `up`; a `box` pixel filter (each sample counts in its own pixel
  only, as in twopass), the `independent` sampler, an RGB `hdrfilm`.
- shapes: `polygon` as a triangle fan in the file's vertex order, `quad` as two triangles,
  `box` as twelve triangles facing out, each with flat normals (`face_normals`), so the
  one-sided emitters face where twopass's do; `sphere` as Mitsuba's analytic sphere (twopass
  tessellates it finely enough that the difference is below the images' noise); `obj` through
  Mitsuba's own OBJ reader with flat normals when the file has none (twopass invents no
  normals either), one material for the whole file.
- materials: `lambert` as `diffuse`; `mirror` as a `conductor` of perfect reflectance
  (`material: none`, times `specular_reflectance`); `dielectric` as `dielectric` with the
  file's `ior` inside, 1 outside; `conductor` with `ior` and `k` as `conductor` with `eta` and
  `k`. Anything else stops the script with the object and material named: a benchmark on a
  scene it cannot convert exactly would compare different images.
- emission: an `area` emitter with the object's RGB radiance (W/(m^2 sr)), front side only.

Object `transform`s, textures, lamps and `[sky]` are refused for the same reason.
"""

import math
import os
import tomllib

import numpy as np


def _flat_mesh(mi, name, vertices, faces, bsdf, emitter):
    props = mi.Properties()
    props["bsdf"] = bsdf
    if emitter is not None:
        props["emitter"] = emitter
    props["face_normals"] = True
    v = np.asarray(vertices, np.float32)
    f = np.asarray(faces, np.uint32)
    mesh = mi.Mesh(name, len(v), len(f), props)
    params = mi.traverse(mesh)
    params["vertex_positions"] = v.ravel()
    params["faces"] = f.ravel()
    params.update()
    return mesh


def _bsdf(mi, m):
    kind = m["type"]
    if kind == "lambert":
        return {"type": "diffuse", "reflectance": _rgb(m["diffuse"])}
    if kind == "mirror":
        return {"type": "conductor", "material": "none",
                "specular_reflectance": _rgb(m.get("reflectance", 1.0))}
    if kind == "dielectric":
        return {"type": "dielectric", "int_ior": float(m["ior"]), "ext_ior": 1.0}
    if kind == "conductor" and "ior" in m and "k" in m:
        return {"type": "conductor", "eta": _rgb(m["ior"]), "k": _rgb(m["k"])}
    raise SystemExit(f"material {m['name']}: type {kind!r} is not converted to Mitsuba")


def _rgb(value):
    if isinstance(value, (int, float)):
        value = [value] * 3
    return {"type": "rgb", "value": [float(c) for c in value]}


def scene_dict(mi, scene_file, width, height):
    """The twopass scene file as a Mitsuba scene dictionary (`mi.load_dict` takes it)."""
    with open(scene_file, "rb") as f:
        s = tomllib.load(f)
    for key in ("light", "sky", "portal"):
        if key in s:
            raise SystemExit(f"{scene_file}: `{key}` tables are not converted to Mitsuba")
    folder = os.path.dirname(os.path.abspath(scene_file))
    cam = s["camera"]
    film_w, film_h = cam.get("film_size", [25, 25])
    fov_y = math.degrees(2.0 * math.atan(0.5 * film_h / cam["focal_length"]))
    materials = {m["name"]: m for m in s["material"]}
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 64, "rr_depth": 3, "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": fov_y,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])
            ),
            "sampler": {"type": "independent", "sample_count": 1},
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
    }
    for i, obj in enumerate(s["object"]):
        if "transform" in obj:
            raise SystemExit(f"object {obj['name']}: transforms are not converted to Mitsuba")
        shape = obj["shape"]
        m = materials[obj["material"]]
        if "texture" in m or "diffuse_texture" in m:
            raise SystemExit(f"material {m['name']}: textures are not converted to Mitsuba")
        bsdf = mi.load_dict(_bsdf(mi, m))
        emitter = None
        if "emission" in obj:
            emitter = mi.load_dict({"type": "area", "radiance": _rgb(obj["emission"])})
        key = f"shape_{i:03d}_{obj['name']}"
        kind = shape["type"]
        if kind == "polygon":
            v = shape["vertices"]
            faces = [[0, k, k + 1] for k in range(1, len(v) - 1)]
            d[key] = _flat_mesh(mi, obj["name"], v, faces, bsdf, emitter)
        elif kind == "quad":
            o, u, w = (np.asarray(shape[k], np.float64) for k in ("origin", "edge_u", "edge_v"))
            v = [o, o + u, o + u + w, o + w]
            d[key] = _flat_mesh(mi, obj["name"], v, [[0, 1, 2], [0, 2, 3]], bsdf, emitter)
        elif kind == "box":
            lo, hi = np.asarray(shape["min"], np.float64), np.asarray(shape["max"], np.float64)
            v = [[(hi if (c >> a) & 1 else lo)[a] for a in range(3)] for c in range(8)]
            # Corner c has x from bit 0, y from bit 1, z from bit 2; each face counter-clockwise
            # seen from outside.
            quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1],
                     [4, 5, 7, 6]]
            faces = [t for q in quads for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])]
            d[key] = _flat_mesh(mi, obj["name"], v, faces, bsdf, emitter)
        elif kind == "sphere":
            sphere = {"type": "sphere", "center": [float(c) for c in shape["center"]],
                      "radius": float(shape["radius"]), "bsdf": bsdf}
            if emitter is not None:
                sphere["emitter"] = emitter
            d[key] = sphere
        elif kind == "obj":
            path = os.path.join(folder, shape["file"])
            with open(path) as f:
                text = f.read()
            if "\nvn " in text or text.startswith("vn ") or "mtllib" in text:
                raise SystemExit(f"{path}: normals and MTL libraries are not converted")
            mesh = {"type": "obj", "filename": path, "face_normals": True, "bsdf": bsdf}
            if emitter is not None:
                mesh["emitter"] = emitter
            d[key] = mesh
        else:
            raise SystemExit(f"object {obj['name']}: shape {kind!r} is not converted to Mitsuba")
    return d
