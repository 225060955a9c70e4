//! Motion autoencoder: conv encoder → quantizer → conv decoder.
