# tinsmith — multi-stage image on Debian bookworm.
# builder: the same tools/setup.sh a developer runs (Debian's node and npm
# with it), then a Release build and the viewer's npm packages.
# runtime: only the shared libraries the binary links, the binary, the
# viewer's pages and the library files they load, non-root.
FROM debian:bookworm AS builder
WORKDIR /src
COPY tools/setup.sh tools/setup.sh
RUN bash tools/setup.sh && rm -rf /var/lib/apt/lists/*
COPY . .
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DTINSMITH_TESTS=OFF -DTINSMITH_BENCHMARKS=OFF \
 && cmake --build build -j"$(nproc)" --target tinsmith \
 && strip build/bin/tinsmith
# The viewer (server/viewer/package-lock.json), staged in /viewer as
# /usr/share/tinsmith/viewer will hold it: the pages, and of node_modules
# only the trees the server serves (server/app/viewer_assets.hpp) with the
# packages' licences.
RUN npm ci --prefix server/viewer --no-audit --no-fund --loglevel=error \
 && mkdir -p /viewer \
 && cp server/viewer/*.html server/viewer/*.js server/viewer/*.css /viewer/ \
 && for tree in cesium/Build/Cesium three/build three/examples/jsm 3d-tiles-renderer/build; do \
      mkdir -p "/viewer/node_modules/$tree" \
      && cp -a "server/viewer/node_modules/$tree/." "/viewer/node_modules/$tree/"; \
    done \
 && cp server/viewer/node_modules/cesium/LICENSE.md /viewer/node_modules/cesium/ \
 && cp server/viewer/node_modules/three/LICENSE /viewer/node_modules/three/ \
 && cp server/viewer/node_modules/3d-tiles-renderer/LICENSE /viewer/node_modules/3d-tiles-renderer/

FROM debian:bookworm AS runtime
# The packages of the libraries the binary links (readelf -d: NEEDED; checked
# against ldd build/release/bin/tinsmith), plus proj-data (proj.db and the
# EGM96 grid) and curl for the health check. tinygltf is linked away (only
# its headers are used) and nothing links libgomp, so neither is here.
RUN apt-get update \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      libgdal32 libproj25 proj-data libgeographiclib23 libopenexr-3-1-30 libimath-3-1-29 libdraco7 \
      libsqlite3-0 libtomlplusplus3 zlib1g libbrotli1 \
      curl \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --create-home --home-dir /var/lib/tinsmith tinsmith
COPY --from=builder /src/build/bin/tinsmith /usr/local/bin/tinsmith
# Where `tinsmith serve` looks for the viewer (after ../share beside the binary).
COPY --from=builder /viewer /usr/share/tinsmith/viewer
USER tinsmith
WORKDIR /var/lib/tinsmith
VOLUME ["/var/lib/tinsmith/stores"]
EXPOSE 8080
HEALTHCHECK --interval=30s --timeout=3s --start-period=5s \
  CMD curl -fsS http://127.0.0.1:8080/health || exit 1
ENTRYPOINT ["tinsmith"]
CMD ["serve", "--host", "0.0.0.0", "--port", "8080", "/var/lib/tinsmith/stores"]
