// Entry of the three.js bundle the viewer loads as a classic script (global THREE): three.js
// itself plus the two add-ons the page uses.
export * from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
export { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
