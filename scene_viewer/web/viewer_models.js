// Instanced drawing of the scene viewer page's class models (viewer.js, viewer_drive.js): every
// placed copy of the same primitive (geometry and material) is one instance of one
// THREE.InstancedMesh, so 50 cars of 6 primitives take 6 draw calls instead of 300 (on a
// software WebGL each call costs). A classic script: it sets window.SceneViewerModels.
(function () {
    'use strict';

    /// Batches the meshes under each item's `root` (placed in the world frame, not in a scene)
    /// by geometry and material. An item is drawn while `item.object.visible` holds (sync()
    /// applies changes); itemOf(hit) maps a raycaster hit on a batch back to its item.
    function create(entries) {
        const batches = new Map();  // geometry + material ids -> {geometry, material, copies}
        for (const { item, root } of entries) {
            root.updateMatrixWorld(true);
            root.traverse((o) => {
                if (!o.isMesh) return;
                const materials = Array.isArray(o.material) ? o.material : [o.material];
                const key = o.geometry.uuid + '|' + materials.map((m) => m.uuid).join(',');
                let batch = batches.get(key);
                if (!batch) {
                    batch = { geometry: o.geometry, material: o.material, copies: [] };
                    batches.set(key, batch);
                }
                batch.copies.push({ item, matrix: o.matrixWorld.clone() });
            });
        }
        const group = new THREE.Group();
        const meshes = [];
        for (const batch of batches.values()) {
            const mesh = new THREE.InstancedMesh(batch.geometry, batch.material, batch.copies.length);
            mesh.userData.copies = batch.copies;
            mesh.userData.drawn = [];  // instance id -> item
            mesh.frustumCulled = false;
            meshes.push(mesh);
            group.add(mesh);
        }

        /// Draws the copies of the visible items only.
        function sync() {
            for (const mesh of meshes) {
                const drawn = [];
                for (const copy of mesh.userData.copies) {
                    if (!copy.item.object.visible) continue;
                    mesh.setMatrixAt(drawn.length, copy.matrix);
                    drawn.push(copy.item);
                }
                mesh.userData.drawn = drawn;
                mesh.count = drawn.length;
                mesh.visible = drawn.length > 0;
                mesh.instanceMatrix.needsUpdate = true;
                mesh.boundingSphere = null;  // raycasting recomputes it over the drawn copies
            }
        }
        sync();
        return {
            group,
            meshes,
            sync,
            itemOf: (hit) => (hit.object.userData.drawn || [])[hit.instanceId] || null,
        };
    }

    window.SceneViewerModels = { create };
})();
