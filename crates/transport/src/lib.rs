//! Physical snow transport after Jubert 2018: scene voxelisation, 3D wind by Stable Fluids, precipitation maps, terrain wind modification, saltation, suspension, sublimation and melt (SnowTran-3D).
