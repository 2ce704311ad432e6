//! Triangle-mesh scenes for the mesh snow methods: OBJ/glTF/PLY input with validation, ray casting, snow-mesh output (glb, OBJ) and CPU previews.
