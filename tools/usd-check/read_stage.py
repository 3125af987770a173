"""Reads a USD stage with Pixar's own library (PyPI's usd-core) and prints what a tool importing
it sees, as JSON: the stage's time range and rate, and for each mesh prim its face counts and
indices, its subsets and its points at every time code. The tests compare this with the run's
frames. Exit 2 when the stage does not open or has no meshes; errors of USD's validators
(every validator USD registers) are listed under "compliance"."""

import json
import sys

from pxr import Usd, UsdGeom, UsdValidation


def main(path):
    stage = Usd.Stage.Open(path)
    if stage is None:
        print(f"{path}: USD cannot open it", file=sys.stderr)
        return 2
    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    out = {
        "start": start,
        "end": end,
        "fps": stage.GetTimeCodesPerSecond(),
        "up": UsdGeom.GetStageUpAxis(stage),
        "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
        "default_prim": str(stage.GetDefaultPrim().GetPath()),
        "meshes": {},
    }
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr()
        times = points.GetTimeSamples()
        out["meshes"][prim.GetName()] = {
            "counts": list(mesh.GetFaceVertexCountsAttr().Get()),
            "indices": list(mesh.GetFaceVertexIndicesAttr().Get()),
            "times": list(times),
            "samples": [[list(p) for p in points.Get(t)] for t in times],
            "subsets": {
                s.GetPrim().GetName(): list(s.GetIndicesAttr().Get())
                for s in UsdGeom.Subset.GetAllGeomSubsets(UsdGeom.Imageable(prim))
            },
        }
    if not out["meshes"]:
        print(f"{path}: no mesh prims", file=sys.stderr)
        return 2
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    errors = UsdValidation.ValidationContext(validators).Validate(stage)
    out["validators"] = len(validators)
    out["compliance"] = [f"{e.GetName()}: {e.GetMessage()}" for e in errors]
    json.dump(out, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
