//! Growing Cells Radiosity: radiosity on evolving networks (Bohn 2000).
