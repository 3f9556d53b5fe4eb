// Constants the build defines (vite.config.js), and what the studio's JSX uses of React's types.
import "react";

declare global {
  /** True in the end-to-end tests' build (`vite build --mode e2e`), false in the studio's own. */
  const __TEST_HOOK__: boolean;
}

declare module "react" {
  // CSS custom properties in inline styles (a port's colour: "--port-color")
  interface CSSProperties {
    [key: `--${string}`]: string | number | undefined;
  }
}
