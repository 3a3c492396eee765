/* LD_PRELOADed by deploy/test-sanitize only: dlclose() does nothing, so the
 * shared objects Mesa loads at run time (swrast_dri.so, libLLVM, ...) stay
 * mapped until exit and LeakSanitizer can name them in its stacks. Without
 * it their frames print as "<unknown module>" and no suppression can match.
 * Nothing is unloaded early in a test process anyway. */
int dlclose(void* handle) {
  (void)handle;
  return 0;
}
