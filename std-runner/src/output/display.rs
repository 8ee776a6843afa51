//! What a PNG shows: chosen bands as colours (see [`DisplayBands`]) or one band through a
//! colour map with a labelled bar (see [`super::colorbar`]).
//!
//! Default: for a PAR/NIR scene (2 bands named `par` and `nir`, any case) the PAR band's
//! radiosity through the colour map, the publishable picture of a canopy; for any other
//! scene the bands as colours (grey, false colour or RGB, as [`DisplayBands::default_for`]).
//! `--display-bands` implies bands.

use super::colorbar::MapDisplay;
use super::png_file::DisplayBands;

/// `--display`: how a PNG shows the bands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DisplayMode {
    /// One band (PAR if the scene has one, else the first) as radiosity (W/m^2) through
    /// the viridis colour map, with a labelled colour bar.
    Map,
    /// Bands as colours: grey, false colour or red, green, blue (see --display-bands).
    Bands,
}

/// What a PNG shows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Display {
    /// Bands as display colours.
    Bands(DisplayBands),
    /// One band through the colour map.
    Map(MapDisplay),
}

impl From<DisplayBands> for Display {
    fn from(d: DisplayBands) -> Self {
        Display::Bands(d)
    }
}

/// True when the scene's bands are exactly `par` and `nir` (any case, either order).
pub fn is_par_nir(names: &[String]) -> bool {
    let mut lower: Vec<String> = names.iter().map(|n| n.to_ascii_lowercase()).collect();
    lower.sort();
    lower == ["nir", "par"]
}

impl Display {
    /// The default for a scene of `bands` bands named `names` (see the module).
    pub fn default_for(bands: usize, names: &[String]) -> Self {
        if bands == 2 && is_par_nir(names) {
            Display::Map(Self::map_of(bands, names))
        } else {
            Display::Bands(DisplayBands::default_for(bands))
        }
    }

    /// The colour map of the band named `par`, else of band 0.
    fn map_of(bands: usize, names: &[String]) -> MapDisplay {
        let band = names
            .iter()
            .position(|n| n.eq_ignore_ascii_case("par"))
            .filter(|&b| b < bands)
            .unwrap_or(0);
        let name = match names.get(band).filter(|n| !n.is_empty()) {
            Some(n) => n.to_ascii_uppercase(),
            None => format!("BAND {band}"),
        };
        MapDisplay { band, name }
    }

    /// From `--display` and `--display-bands` (which implies `bands`; with `map` it is
    /// refused).
    pub fn choose(
        mode: Option<DisplayMode>,
        spec: Option<&str>,
        bands: usize,
        names: &[String],
    ) -> Result<Self, String> {
        match (mode, spec) {
            (Some(DisplayMode::Map), Some(_)) => Err(
                "--display-bands chooses the bands shown as colours; it does not go with --display map"
                    .into(),
            ),
            (_, Some(spec)) => Ok(Display::Bands(DisplayBands::parse(spec, bands, names)?)),
            (Some(DisplayMode::Map), None) => Ok(Display::Map(Self::map_of(bands, names))),
            (Some(DisplayMode::Bands), None) => {
                Ok(Display::Bands(DisplayBands::default_for(bands)))
            }
            (None, None) => Ok(Self::default_for(bands, names)),
        }
    }

    /// `red = nir, green = par, blue = par`, `grey = par`, or `PAR radiosity (W/m^2)
    /// through the viridis colour map`.
    pub fn describe(&self, names: &[String]) -> String {
        match self {
            Display::Bands(d) => d.describe(names),
            Display::Map(m) => format!(
                "{} radiosity (W/m^2) through the viridis colour map, with a colour bar",
                m.name
            ),
        }
    }

    /// The note `hirad solve` prints about a PNG: what it shows and, unless the bands were
    /// `chosen` with `--display-bands`, how to choose; `None` when nothing needs saying (an
    /// RGB scene in its own colours).
    pub fn note(&self, bands: usize, names: &[String], chosen: bool) -> Option<String> {
        let why = if chosen {
            ""
        } else {
            match self {
                Display::Map(_) => " (--display bands shows the bands as colours)",
                Display::Bands(_) if bands == 3 => return None,
                Display::Bands(_) if bands == 2 => {
                    " (false colour, as colour-infrared pictures; --display-bands chooses)"
                }
                Display::Bands(_) if bands > 3 => {
                    " (the first three bands; --display-bands chooses)"
                }
                Display::Bands(_) => " (--display-bands chooses)",
            }
        };
        Some(format!("{}{why}", self.describe(names)))
    }
}
