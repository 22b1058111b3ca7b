//! Readers and writers: gmsh MSH (4.1 and 2.2, ASCII and binary), VTU, JSON.
