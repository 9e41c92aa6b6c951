// A three.js view (z up, orbiting camera) that renders only when something changed: headless
// and software-rendered browsers draw WebGL on the CPU, so no animation loop runs idle.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

export const BACKGROUND = 0xe9edf2;

export function createViewer(container, { position = [5.5, -6.5, 5.0], target = [0, 0, 0.6] } = {}) {
  // preserveDrawingBuffer: the page's pixels can be read back (tests, screenshots).
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  const width = container.clientWidth || 900, height = container.clientHeight || 500;
  renderer.setSize(width, height);
  renderer.setClearColor(BACKGROUND);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(45, width / height, 0.02, 200);
  camera.up.set(0, 0, 1);
  camera.position.set(...position);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(...target);
  controls.update();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.4);
  sun.position.set(3, -4, 8);
  scene.add(sun);
  // Draw only while on screen: software WebGL (headless Chromium, no GPU) takes a good part of a
  // second to set up and draw a view, and a view below the fold need not delay the page.
  let queued = false, visible = false, stale = true;
  const render = () => {
    stale = true;
    if (queued || !visible) return;
    queued = true;
    requestAnimationFrame(() => { queued = false; stale = false; renderer.render(scene, camera); });
  };
  new IntersectionObserver((entries) => {
    visible = entries.some((e) => e.isIntersecting);
    if (visible && stale) render();
  }).observe(container);
  const renderNow = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  // Lit pixels (not background) and red ones of the canvas: for tests of what was drawn.
  const litPixels = () => {
    renderNow();
    const c = renderer.domElement, tmp = document.createElement('canvas');
    tmp.width = c.width; tmp.height = c.height;
    const g = tmp.getContext('2d');
    g.drawImage(c, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const br = (BACKGROUND >> 16) & 255, bg = (BACKGROUND >> 8) & 255, bb = BACKGROUND & 255;
    let lit = 0, red = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - br) + Math.abs(d[i + 1] - bg) + Math.abs(d[i + 2] - bb) > 24) lit++;
      if (d[i] > d[i + 1] + 50 && d[i] > d[i + 2] + 50) red++;  // reddish, also when blended
    }
    return { lit, red, total: c.width * c.height, url: c.toDataURL() };
  };
  return { THREE, scene, camera, renderer, controls, render, renderNow, litPixels, canvas: renderer.domElement };
}

export function boxMesh(size, color, opacity = 1) {
  const m = new THREE.MeshLambertMaterial({ color, transparent: opacity < 1, opacity, depthWrite: opacity >= 1 });
  return new THREE.Mesh(new THREE.BoxGeometry(size[0], size[1], size[2]), m);
}

export const mat4 = (a) => new THREE.Matrix4().fromArray(a);
