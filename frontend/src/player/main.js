// The animation player: the page `res.animate("anim.html")` writes holds the Animation as JSON
// in <script type="application/json" id="kinetwork-animation"> and this script, built into
// kinetwork/assets/player.js (one IIFE, three.js included). It plays the animation in
// #kinetwork-player (or the body) with its controls; `window.kinetworkPlayer` is the viewer,
// and `KinetworkPlayer.createViewer` makes more (the script defines the global KinetworkPlayer).
import { createViewer } from "../viewer3d/index.js";

export { createViewer };

function start() {
  const root = document.getElementById("kinetwork-player") || document.body;
  const node = document.getElementById("kinetwork-animation");
  if (!node) {
    root.textContent = "This page holds no kinetwork animation.";
    return;
  }
  const animation = JSON.parse(node.textContent);
  /** @type {any} */ (window).kinetworkPlayer = createViewer(root, animation, { controls: true, autoplay: true });
}

if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
else start();
