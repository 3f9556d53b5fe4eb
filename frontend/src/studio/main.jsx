import { createRoot } from "react-dom/client";
import { ReactFlowProvider } from "@xyflow/react";
import "@xyflow/react/dist/style.css";
import "./styles.css";
import App from "./App.jsx";
import { useStudio } from "./store.js";
import { TESTING, trace } from "./testing.js";
import { installTestHook } from "./testhook.js";

if (TESTING) {
  trace.timings.start = performance.now();
  installTestHook(useStudio);
}

createRoot(document.getElementById("root")).render(
  <ReactFlowProvider>
    <App />
  </ReactFlowProvider>,
);
