"""Make the small gmsh meshes used by tests/mesh_io.rs.

Run from the crate root with the PyPI `gmsh` package (`pip install gmsh`):

    python3 tests/data/make_test_meshes.py

The outputs are committed, so the Rust tests do not need gmsh. Every box file holds the same
mesh (one gmsh run, saved in several formats), so the tests can check that all readers agree:

- box: 1 x 0.4 x 0.2 box, quadratic tetrahedra (tet10), physical groups
  "body" (3D), "fixed" (2D, face x = 0) and "load" (2D, face x = 1).
- box_41.msh        MSH 4.1 ASCII
- box_41_bin.msh    MSH 4.1 binary
- box_41_param.msh  MSH 4.1 ASCII with parametric node coordinates (Mesh.SaveParametric = 1)
- box_41_param_bin.msh  MSH 4.1 binary with parametric node coordinates
- box_22.msh        MSH 2.2 ASCII
- box_22_bin.msh    MSH 2.2 binary
- nophys_41.msh / nophys_22.msh: a coarse linear-tet box without physical groups (all elements
  saved).
- two_groups_41.msh / two_groups_22.msh / two_groups_22_bin.msh: a coarse linear-tet cube whose
  volume is in two physical groups "a" and "b" (MSH 2.2 repeats each element once per group).
- pyramid_41.msh / pyramid_22.msh: one pyramid (gmsh type 7, unsupported by vibrofem) in the
  physical group "pyr".
"""

import os

import gmsh

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "meshes")


def save(name, version, binary=False, parametric=False):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.option.setNumber("Mesh.SaveParametric", 1 if parametric else 0)
    gmsh.write(os.path.join(HERE, name))


def box():
    gmsh.model.add("box")
    gmsh.model.occ.addBox(0, 0, 0, 1.0, 0.4, 0.2)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.45)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.45)
    surfaces = gmsh.model.getEntities(2)
    fixed, load = [], []
    for dim, tag in surfaces:
        x, _, _ = gmsh.model.occ.getCenterOfMass(dim, tag)
        if abs(x) < 1e-9:
            fixed.append(tag)
        elif abs(x - 1.0) < 1e-9:
            load.append(tag)
    gmsh.model.addPhysicalGroup(3, [1], name="body")
    gmsh.model.addPhysicalGroup(2, fixed, name="fixed")
    gmsh.model.addPhysicalGroup(2, load, name="load")
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    save("box_41.msh", 4.1)
    save("box_41_bin.msh", 4.1, binary=True)
    save("box_41_param.msh", 4.1, parametric=True)
    save("box_41_param_bin.msh", 4.1, binary=True, parametric=True)
    save("box_22.msh", 2.2)
    save("box_22_bin.msh", 2.2, binary=True)
    gmsh.model.remove()


def nophys():
    gmsh.model.add("nophys")
    gmsh.model.occ.addBox(0, 0, 0, 1.0, 1.0, 1.0)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", 1.0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0)
    gmsh.model.mesh.generate(3)
    save("nophys_41.msh", 4.1)
    save("nophys_22.msh", 2.2)
    gmsh.model.remove()


def two_groups():
    gmsh.model.add("two_groups")
    gmsh.model.occ.addBox(0, 0, 0, 1.0, 1.0, 1.0)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", 2.0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 2.0)
    gmsh.model.addPhysicalGroup(3, [1], name="a")
    gmsh.model.addPhysicalGroup(3, [1], name="b")
    gmsh.model.mesh.generate(3)
    save("two_groups_41.msh", 4.1)
    save("two_groups_22.msh", 2.2)
    save("two_groups_22_bin.msh", 2.2, binary=True)
    gmsh.model.remove()


def pyramid():
    gmsh.model.add("pyramid")
    vol = gmsh.model.addDiscreteEntity(3)
    coords = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1]
    gmsh.model.mesh.addNodes(3, vol, [1, 2, 3, 4, 5], coords)
    gmsh.model.mesh.addElements(3, vol, [7], [[1]], [[1, 2, 3, 4, 5]])
    gmsh.model.addPhysicalGroup(3, [vol], name="pyr")
    save("pyramid_41.msh", 4.1)
    save("pyramid_22.msh", 2.2)
    gmsh.model.remove()


if __name__ == "__main__":
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    box()
    nophys()
    two_groups()
    pyramid()
    gmsh.finalize()
