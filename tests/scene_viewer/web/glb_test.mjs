// The .glb export opened by the clients users have: the Khronos glTF validator (npm
// gltf-validator) and three.js's GLTFLoader in Debian's headless chromium. The scene's cars use
// a third-party-style model (double-sided, NEAREST sampler, roughness 0.3, alpha mask) whose
// material must reach the viewer as its author made it; the export must not depend on --view.
// Usage: node glb_test.mjs SCENE_RENDER ENTITIES CLASS_TABLE WORK_DIR NODE_MODULES WEB_DIR CHROMIUM
import { execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';

import { launch, loadModules, serveFolder, skip } from './browser.mjs';

const [sceneRender, entities, classTable, work, nodeModules, webDir, chromium] =
    process.argv.slice(2);
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });

function fail(message) {
    console.error('FAILED: ' + message);
    process.exit(1);
}

function exportGlb(name, ...flags) {
    const out = path.join(work, name);
    execFileSync(sceneRender, [entities, '--classes', classTable, '--glb', out, ...flags],
                 { stdio: ['ignore', 'ignore', 'ignore'] });
    return fs.readFileSync(out);
}

function glbJson(bytes) {
    const length = bytes.readUInt32LE(12);
    return JSON.parse(bytes.subarray(20, 20 + length).toString('utf8'));
}

// 1. The export is the same whatever the view; the ego car only on request.
const camera = exportGlb('camera.glb', '--view', 'camera');
for (const view of ['chase', 'bev', 'free']) {
    if (!camera.equals(exportGlb(view + '.glb', '--view', view))) {
        fail(`--view ${view} exports another .glb than --view camera`);
    }
}
const nodes = glbJson(camera).nodes.length;
const withEgo = glbJson(exportGlb('ego.glb', '--view', 'camera', '--glb-ego')).nodes;
if (withEgo.length !== nodes + 1) fail(`--glb-ego: ${withEgo.length} nodes, expected ${nodes + 1}`);
console.log(`same .glb for the camera, chase, bev and free views (${nodes} nodes); ` +
            `--glb-ego adds one`);

// 2. The Khronos validator finds no error.
const require = createRequire(path.join(path.resolve(nodeModules), 'noop.js'));
let validator;
try {
    validator = require('gltf-validator');
} catch (e) {
    skip('gltf-validator missing in ' + nodeModules + ' (scripts/install-deps.sh)');
}
for (const name of ['camera.glb', 'ego.glb']) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(path.join(work, name))));
    const issues = report.issues;
    console.log(`gltf-validator ${report.validatorVersion}: ${name}: ${issues.numErrors} errors, ` +
                `${issues.numWarnings} warnings, ${issues.numInfos} infos`);
    if (issues.numErrors > 0) {
        fail(name + ': ' + JSON.stringify(issues.messages.filter((m) => m.severity === 0)));
    }
}

// 3. three.js loads it in chromium with the third-party material intact.
if (!fs.existsSync(path.join(webDir, 'three.min.js'))) skip('three.js bundle missing in ' + webDir);
const { playwright } = loadModules(nodeModules);
fs.copyFileSync(path.join(webDir, 'three.min.js'), path.join(work, 'three.min.js'));
fs.writeFileSync(path.join(work, 'index.html'),
                 '<!doctype html><html><head><script src="three.min.js"></script></head></html>');
const server = await serveFolder(work);
const context = await launch(playwright, chromium);
try {
    const page = await context.newPage();
    await page.goto(server.url + 'index.html');
    const seen = await page.evaluate(async () => {
        const buffer = await (await fetch('camera.glb')).arrayBuffer();
        const gltf = await new THREE.GLTFLoader().parseAsync(buffer, '');
        const kit = [];
        gltf.scene.traverse((o) => {
            if (o.isMesh && o.material.name === 'kit') kit.push(o.material);
        });
        const m = kit[0];
        return m && {
            count: kit.length,
            doubleSided: m.side === THREE.DoubleSide,
            nearest: m.map && m.map.magFilter === THREE.NearestFilter &&
                m.map.minFilter === THREE.NearestFilter,
            clamp: m.map && m.map.wrapS === THREE.ClampToEdgeWrapping,
            roughness: m.roughness,
            metalness: m.metalness,
            alphaTest: m.alphaTest,
        };
    });
    if (!seen) fail('three.js found no mesh with the model\'s material "kit"');
    console.log('three.js ' + JSON.stringify(seen));
    if (!seen.doubleSided) fail('the material is not double-sided in three.js');
    if (!seen.nearest) fail('the texture lost its NEAREST filter');
    if (!seen.clamp) fail('the texture lost its CLAMP_TO_EDGE wrap');
    if (Math.abs(seen.roughness - 0.3) > 1e-6 || Math.abs(seen.metalness - 0.5) > 1e-6) {
        fail('roughness/metalness changed');
    }
    if (Math.abs(seen.alphaTest - 0.4) > 1e-6) fail('the alpha cutoff changed');
} finally {
    await context.close();
    server.close();
}
console.log('PASSED');
