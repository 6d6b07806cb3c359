// Octant of a thick-walled sphere, inner radius 1, outer radius 2, as second-order (10-node,
// curved) tets: MixedSolid's curved elements against the closed-form inflation
// (tests/models/fem/curved_mixed_test.cc). The three files were made with Debian 12's Gmsh 4.8.4:
//   for s in 0.7 0.5 0.35; do gmsh -3 -order 2 -format msh41 -setnumber size $s \
//     thick_sphere_octant.geo -o thick_sphere_octant_$s.msh; done
SetFactory("OpenCASCADE");
DefineConstant[ size = 0.5 ];
Sphere(1) = {0, 0, 0, 2, 0, Pi/2, Pi/2};
Sphere(2) = {0, 0, 0, 1, 0, Pi/2, Pi/2};
BooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};
Physical Volume("wall") = {3};
Mesh.MeshSizeMax = size;
Mesh.MeshSizeMin = size;
