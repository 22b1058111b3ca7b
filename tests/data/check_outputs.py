"""Manual check of vibrofem's writers with the real tools (not run by `cargo test`).

    pip install gmsh vtk
    python3 tests/data/check_outputs.py out.msh modes.vtu ...

For a `.msh` file (io::msh_out): gmsh opens it, and the script prints the node and element
counts, the physical groups, the views, and the smallest scaled Jacobian of the 3D elements
(positive for valid, positively oriented cells; 1 for undistorted ones).
For a `.vtu` file (io::vtk): VTK reads it, and the script prints the cell types, the states of
vtkCellValidator (0 = valid, 32 = faces wrongly oriented, ...), the total volume from
vtkCellSizeFilter and the point-data arrays.
"""

import sys


def check_msh(path):
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(path)
    nodes, _, _ = gmsh.model.mesh.getNodes()
    types, tags, _ = gmsh.model.mesh.getElements()
    groups = [
        (d, t, gmsh.model.getPhysicalName(d, t)) for d, t in gmsh.model.getPhysicalGroups()
    ]
    solid = [e for ty, e in zip(types, tags) if ty in (4, 5, 6, 11, 12, 17, 18)]
    min_sj = min(min(gmsh.model.mesh.getElementQualities(e, "minSJ")) for e in solid) if solid else None
    views = [
        gmsh.option.getString(f"View[{gmsh.view.getIndex(v)}].Name") for v in gmsh.view.getTags()
    ]
    print(f"{path}: {len(nodes)} nodes, elements {dict(zip(types, map(len, tags)))}, "
          f"groups {groups}, views {views}, min scaled Jacobian {min_sj}")
    gmsh.finalize()


def check_vtu(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    val = vtk.vtkCellValidator()
    val.SetInputData(g)
    val.Update()
    states = vtk_to_numpy(val.GetOutput().GetCellData().GetArray("ValidityState"))
    size = vtk.vtkCellSizeFilter()
    size.SetInputData(g)
    size.Update()
    volume = vtk_to_numpy(size.GetOutput().GetCellData().GetArray("Volume")).sum()
    types = sorted({g.GetCellType(i) for i in range(g.GetNumberOfCells())})
    arrays = [g.GetPointData().GetArrayName(i) for i in range(g.GetPointData().GetNumberOfArrays())]
    print(f"{path}: {g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} cells of VTK types "
          f"{types}, validity states {sorted(set(states.tolist()))}, volume {volume}, "
          f"point data {arrays}")


if __name__ == "__main__":
    for p in sys.argv[1:]:
        (check_vtu if p.endswith(".vtu") else check_msh)(p)
