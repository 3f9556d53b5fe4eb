// The animation player: one self-contained IIFE script (three.js included) that
// `res.animate()` inlines into a standalone HTML file: no network needed to open it.
import { defineConfig } from "vite";

export default defineConfig({
  build: {
    outDir: "../kinetwork/assets",
    emptyOutDir: false,
    lib: {
      entry: "src/player/main.js",
      name: "KinetworkPlayer",
      formats: ["iife"],
      fileName: () => "player.js",
    },
    chunkSizeWarningLimit: 4000,
  },
});
