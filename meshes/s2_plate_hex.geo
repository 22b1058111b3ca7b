// S2 plate 900 × 400 × 116 mm (shared/spec/scenes.md), structured hexahedra: the box is
// transfinite with ceil(length / size) divisions per edge and recombined, so
// `vibrofem converge` meshes it as hex8 (--orders 1) or hex20 (--orders 2) at each size.
// Units: millimetres (`--length-unit mm`).
//
//   vibrofem converge meshes/s2_plate_hex.geo --length-unit mm --sizes 200,100,50 --orders 2
DefineConstant[ size = 50 ];
SetFactory("OpenCASCADE");
a = 900; b = 400; c = 116;
Box(1) = {0, 0, 0, a, b, c};
Physical Volume("body") = {1};
e = 1e-3;
// Divisions along x, y, z (at least one).
nx = Ceil(a / size - e); ny = Ceil(b / size - e); nz = Ceil(c / size - e);
// Edges along x (y and z at 0 or the far side), y and z: each bounding box holds four edges.
lx() = Curve In BoundingBox{-e, -e, -e, a + e, b + e, c + e};
ex() = {}; ey() = {}; ez() = {};
For i In {0 : #lx() - 1}
  bb() = BoundingBox Curve{lx(i)};
  If (bb(3) - bb(0) > e)
    ex() += lx(i);
  ElseIf (bb(4) - bb(1) > e)
    ey() += lx(i);
  Else
    ez() += lx(i);
  EndIf
EndFor
Transfinite Curve{ex()} = nx + 1;
Transfinite Curve{ey()} = ny + 1;
Transfinite Curve{ez()} = nz + 1;
Transfinite Surface{:};
Recombine Surface{:};
Transfinite Volume{1};
