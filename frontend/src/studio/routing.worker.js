// The routing worker: one router with its memory (a moved block re-routes only its wires),
// answering each request of the page (routeservice.js).
import { WireRouter } from "./routing.js";
import { answer } from "./routeservice.js";

const router = new WireRouter();
self.onmessage = (e) => self.postMessage(answer(router, e.data, "worker"));
