//! Radiosity scenes (OBJ, glTF, Flatland, built-ins), area-uniform sampling, BVH visibility and the radiosity kernel.
