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
- lamps (`[[light]]`): `point` as `point` with the same radiant intensity (W/sr); `spot` as
  `spot` aimed along the lamp's axis, `cutoff_angle` the outer angle and `beam_width` where
  twopass's ramp reaches full intensity, but only when the inner angle is within 0.5 degrees
  of the outer one (a hard-edged cone): between the two the falloffs differ (glTF's t^2 in the
  cosine against Mitsuba's linear ramp in the angle), so a soft spot would compare different
  lights; `directional` as `directional` with the same
  irradiance. `power` becomes intensity as twopass reads it (I = power / 4 pi, spots too).
- sky: `kind = "uniform"` as a `constant` emitter of the same radiance. The daylight sky is
  converted only from a tabulation of twopass's own model written beside the scene file
  (Mitsuba's `sunsky` is Hosek-Wilkie's model, not Preetham's, so a converted sky would be
  another light): `<stem>.sky.exr`, the dome's radiance in Mitsuba's `envmap` layout (pixel
  centre (u, v) is the direction (sin t sin p, cos t, -sin t cos p), t = pi v, p = 2 pi u,
  world +y up), becomes an `envmap`; `<stem>.sun.json` (`direction` toward the sun,
  `one_minus_cos` of the disc's angular radius, `radiance` per channel) becomes a `disk` area
  emitter of that radiance far along the sun's direction, subtending exactly the sun's solid
  angle. This compares how the two engines render a given sky, not the sky models. Without
  the tabulation the daylight sky is refused. Portals only steer twopass's sampling and are
  ignored.

Object `transform`s and textures are refused for the same reason.
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
    folder = os.path.dirname(os.path.abspath(scene_file))
    cam = s["camera"]
    if "fov_y" in cam:
        fov_y = float(cam["fov_y"])
    else:
        _, film_h = cam.get("film_size", [36, 24])
        fov_y = math.degrees(2.0 * math.atan(0.5 * film_h / cam.get("focal_length", 50.0)))
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
    for i, lamp in enumerate(s.get("light", [])):
        d[f"lamp_{i:03d}"] = _lamp(mi, lamp, i)
    if "sky" in s:
        sky = s["sky"]
        if sky["kind"] == "daylight":
            d.update(_tabulated_daylight(mi, scene_file))
        elif sky["kind"] != "uniform":
            raise SystemExit(f"[sky]: kind {sky['kind']!r} is not converted to Mitsuba")
        else:
            radiance = np.asarray(_rgb(sky["radiance"])["value"]) * float(sky.get("scale", 1.0))
            d["sky"] = {"type": "constant", "radiance": _rgb(list(radiance))}
    return d


def _tabulated_daylight(mi, scene_file):
    """The dome as an `envmap` and the sun as a far `disk` emitter, from the tabulation beside
    `scene_file` (see the module's notes)."""
    stem = os.path.splitext(scene_file)[0]
    dome, sun_file = stem + ".sky.exr", stem + ".sun.json"
    if not (os.path.isfile(dome) and os.path.isfile(sun_file)):
        raise SystemExit(
            f"[sky]: a daylight sky is converted only from its tabulation ({dome} and "
            f"{sun_file}, written from twopass's model): Mitsuba's sunsky is another model"
        )
    import json

    with open(sun_file) as f:
        sun = json.load(f)
    out = {"sky": {"type": "envmap", "filename": dome}}
    if sun is not None:
        direction = np.asarray(sun["direction"], np.float64)
        direction /= np.linalg.norm(direction)
        # A disc of radius D tan(a) at distance D subtends 2 pi (1 - cos a), exactly the
        # sun's solid angle; far enough that its distance varies by nothing across the scene.
        cos_a = 1.0 - float(sun["one_minus_cos"])
        distance = 1.0e3
        radius = distance * math.sqrt(1.0 - cos_a * cos_a) / cos_a
        centre = direction * distance
        up = [0.0, 0.0, 1.0] if abs(direction[1]) > 0.9 else [0.0, 1.0, 0.0]
        to_world = mi.ScalarTransform4f().look_at(
            origin=[float(c) for c in centre], target=[float(c) for c in centre - direction], up=up
        ) @ mi.ScalarTransform4f().scale([radius, radius, 1.0])
        out["sun"] = {
            "type": "disk",
            "to_world": to_world,
            "emitter": {"type": "area", "radiance": _rgb(sun["radiance"])},
        }
    return out


def _lamp(mi, lamp, index):
    """A `[[light]]` table as a Mitsuba emitter dictionary."""
    name = lamp.get("name", f"light {index + 1}")
    kind = lamp["kind"]
    colour = np.asarray(_rgb(lamp.get("colour", 1.0))["value"])
    position = np.asarray(lamp.get("position", [0.0, 0.0, 0.0]), np.float64)
    if "direction" in lamp:
        direction = np.asarray(lamp["direction"], np.float64)
    elif "look_at" in lamp:
        direction = np.asarray(lamp["look_at"], np.float64) - position
    else:
        direction = None
    if kind == "directional":
        return {"type": "directional", "direction": [float(c) for c in direction],
                "irradiance": _rgb(list(float(lamp["irradiance"]) * colour))}
    if "intensity" in lamp:
        intensity = np.asarray(_rgb(lamp["intensity"])["value"])
    else:
        intensity = np.full(3, float(lamp["power"]) / (4.0 * math.pi))
    intensity = _rgb(list(intensity * colour))
    if kind == "point":
        return {"type": "point", "position": [float(c) for c in position], "intensity": intensity}
    if kind == "spot":
        inner, outer = float(lamp.get("inner_angle", 0.0)), float(lamp.get("outer_angle", 45.0))
        if outer - inner > 0.5:
            raise SystemExit(
                f"light {name}: a spot whose falloff spans {outer - inner} degrees is not "
                "converted (the falloffs differ); give inner_angle within 0.5 of outer_angle"
            )
        # Any up that is not along the axis.
        axis = direction / np.linalg.norm(direction)
        up = [0.0, 0.0, 1.0] if abs(axis[1]) > 0.9 else [0.0, 1.0, 0.0]
        return {
            "type": "spot",
            "intensity": intensity,
            "cutoff_angle": outer,
            # Full intensity inside the angle where twopass's ramp reaches 1 (its ramp spans at
            # least 0.001 in the cosine, even when the two angles are equal).
            "beam_width": math.degrees(math.acos(min(1.0, math.cos(math.radians(outer))
                                                     + max(0.001, math.cos(math.radians(inner))
                                                           - math.cos(math.radians(outer)))))),
            "to_world": mi.ScalarTransform4f().look_at(
                origin=list(position), target=list(position + axis), up=up
            ),
        }
    raise SystemExit(f"light {name}: kind {kind!r} is not converted to Mitsuba")
