// The studio: a single-page app served by `kinetwork studio` from kinetwork/studio/static.
// `vite build --mode e2e --outDir DIR` builds the same app with the end-to-end tests' hook
// (window.__kinetwork, see src/studio/testing.js) into DIR; the studio's own build has none.
import { defineConfig } from "vite";
import react from "@vitejs/plugin-react";

export default defineConfig(({ mode }) => ({
  plugins: [react()],
  root: "src/studio",
  base: "./",
  define: { __TEST_HOOK__: JSON.stringify(mode === "e2e") },
  build: {
    outDir: "../../../kinetwork/studio/static",
    emptyOutDir: true,
    chunkSizeWarningLimit: 4000,
  },
  test: {
    root: ".",
    include: ["tests/**/*.test.js"],
    environment: "node",
  },
}));
