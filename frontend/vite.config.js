// The studio: a single-page app served by `kinetwork studio` from kinetwork/studio/static.
import { defineConfig } from "vite";
import react from "@vitejs/plugin-react";

export default defineConfig({
  plugins: [react()],
  root: "src/studio",
  base: "./",
  build: {
    outDir: "../../../kinetwork/studio/static",
    emptyOutDir: true,
    chunkSizeWarningLimit: 4000,
  },
});
