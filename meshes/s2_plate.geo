// S2: large thick steel plate 900 × 400 × 116 mm, free-free (shared/spec/scenes.md, S2).
// Published first elastic frequency (mode 7) 722.01 Hz; converged 722.67 Hz (docs/validation.md,
// hex20). Units: millimetres (give `--length-unit mm`, and sizes in mm).
//
//   vibrofem converge meshes/s2_plate.geo --length-unit mm --sizes 200,100,50 --orders 1,2
//
// No supports, so no boundary groups are needed; the faces are named anyway (xmin … zmax) for
// studies that fix or load one of them. `size` is the level's element size when meshed by
// `vibrofem converge` (gmsh's Mesh.MeshSizeMax is set to it as well); 50 mm on its own.
DefineConstant[ size = 50 ];
SetFactory("OpenCASCADE");
a = 900; b = 400; c = 116;
Box(1) = {0, 0, 0, a, b, c};
Physical Volume("body") = {1};
e = 1e-3;
Physical Surface("xmin") = Surface In BoundingBox{-e, -e, -e, e, b + e, c + e};
Physical Surface("xmax") = Surface In BoundingBox{a - e, -e, -e, a + e, b + e, c + e};
Physical Surface("ymin") = Surface In BoundingBox{-e, -e, -e, a + e, e, c + e};
Physical Surface("ymax") = Surface In BoundingBox{-e, b - e, -e, a + e, b + e, c + e};
Physical Surface("zmin") = Surface In BoundingBox{-e, -e, -e, a + e, b + e, e};
Physical Surface("zmax") = Surface In BoundingBox{-e, -e, c - e, a + e, b + e, c + e};
