"""Objects to transfer: meshes, convex hulls, mass properties, procedural starter cores.

Public surface:

- `load_mesh` / `MeshError`: user STL/OBJ/PLY files in metres, checked and repaired.
- `mass_properties` / `MassProperties`: uniform-density rigid-body properties;
  `axial_mass_split` / `AxialSplit`: two densities split across x (a shifted centre of mass).
- `decompose_hulls`: CoACD convex decomposition, cached on disk by content hash.
- `load_object` / `ObjectModel` / `export_object`: a built-in core or a user mesh,
  ready for the simulation, in the object frame F_O (+x to the pinion, +y away
  from the solenoid, +z up on face 'front', origin at the centre of mass).
- `builtin_ids`, `core_spec` / `CoreSpec`, `generate_core`: the 37 procedural
  starter-motor cores o1..o37 (the study's object set, Eq. 5.3).
- `Protrusion` / `ProxySpec` / `proxy_model`: calibrated proxies (features below a face and
  a centre-of-mass shift along x);
  `features_document` / `prior_features` / `features_version`: the built-in cores' shipped
  resting features (`load_builtin(id, features=False)` is the plain body).
"""

from transfertwin.objects._builtin import (
    BuiltinDataError,
    builtin_features,
    builtin_ids,
    features_version,
    is_builtin_id,
    load_builtin,
)
from transfertwin.objects._core_draw import core_spec
from transfertwin.objects._core_spec import BUILTIN_COUNT, CoreSpec, Dent
from transfertwin.objects._cores import generate_core
from transfertwin.objects._features import features_document, prior_features
from transfertwin.objects._hulls import decompose_hulls, default_cache_dir, merge_hulls
from transfertwin.objects._load import export_object, hull_cache_path, load_object
from transfertwin.objects._mass import (
    DEFAULT_DENSITY_KG_M3,
    AxialSplit,
    MassProperties,
    axial_mass_split,
    mass_properties,
)
from transfertwin.objects._mesh import UNITS_TO_M, MeshError, load_mesh
from transfertwin.objects._model import ObjectModel
from transfertwin.objects._proxy import (
    MAX_COM_SHIFT_M,
    PROXY_SUFFIX,
    Protrusion,
    ProxySpec,
    mass_split,
    proxy_model,
    read_proxy,
    write_proxy,
)

__all__ = [
    "BUILTIN_COUNT",
    "DEFAULT_DENSITY_KG_M3",
    "MAX_COM_SHIFT_M",
    "PROXY_SUFFIX",
    "UNITS_TO_M",
    "AxialSplit",
    "BuiltinDataError",
    "CoreSpec",
    "Dent",
    "MassProperties",
    "MeshError",
    "ObjectModel",
    "Protrusion",
    "ProxySpec",
    "axial_mass_split",
    "builtin_features",
    "builtin_ids",
    "core_spec",
    "decompose_hulls",
    "default_cache_dir",
    "export_object",
    "features_document",
    "features_version",
    "generate_core",
    "hull_cache_path",
    "is_builtin_id",
    "load_builtin",
    "load_mesh",
    "load_object",
    "mass_properties",
    "mass_split",
    "merge_hulls",
    "prior_features",
    "proxy_model",
    "read_proxy",
    "write_proxy",
]
